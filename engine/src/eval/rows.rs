//! The rows of `engine eval`: every mode and every knob that trades speed
//! for accuracy, as typed play options — each also written as the main
//! command's flags, so `engine <flags>` replays what a row measured.

use crate::backend::Filtering;
use crate::options::{Maps, Mode, PemOptions, RoomShading, TraceFrames};
use crate::pem::settings::Compositing;
use inference::scene::ViewBlend;
use std::collections::BTreeMap;

/// One row: a label, the mode and its knobs.
#[derive(Clone, Debug)]
pub struct Row {
    pub label: String,
    pub mode: Mode,
    pub pem: PemOptions,
    /// A traced row's samples per pixel and seed.
    pub trace: TraceFrames,
}

/// The row whose frames are the references traced again with another
/// seed at their own samples per pixel: what the references' noise alone
/// scores (a noise-free frame would score about 3 dB higher, half the
/// squared error).
pub const REFERENCE_NOISE: &str = "trace reference-noise";

impl Row {
    fn new(label: &str, mode: Mode) -> Self {
        Self {
            label: label.into(),
            mode,
            pem: PemOptions::default(),
            trace: TraceFrames::default(),
        }
    }
    fn with(mut self, f: impl FnOnce(&mut PemOptions)) -> Self {
        f(&mut self.pem);
        self
    }

    /// The row as measured against references traced at `spp`: the
    /// [`REFERENCE_NOISE`] row traces at their samples per pixel.
    pub fn against_references(mut self, spp: u32) -> Row {
        if self.label == REFERENCE_NOISE {
            self.trace.spp = spp;
        }
        self
    }

    /// The main command's flags this row stands for.
    pub fn flags(&self) -> String {
        let mut words = vec![format!("--mode {}", self.mode.name())];
        for (name, value) in self.pem.flags() {
            words.push(match value {
                Some(v) => format!("--{name} {v}"),
                None => format!("--{name}"),
            });
        }
        if self.mode == Mode::Trace {
            words.push(format!("--trace-spp {}", self.trace.spp));
            if self.trace.seed != 0 {
                words.push(format!("--trace-seed {}", self.trace.seed));
            }
        }
        words.join(" ")
    }

    /// The row's settings for `eval.json`: its label and its knobs that
    /// differ from the defaults, by flag name (`no_blend: true`, `spacing: 4`).
    pub fn settings(&self) -> BTreeMap<String, serde_json::Value> {
        let mut settings = BTreeMap::new();
        settings.insert("label".into(), serde_json::Value::from(self.label.as_str()));
        for (name, value) in self.pem.flags() {
            let v = match value {
                None => serde_json::Value::Bool(true),
                Some(v) => v.parse::<u64>().map_or_else(
                    |_| serde_json::Value::from(v.as_str()),
                    serde_json::Value::from,
                ),
            };
            settings.insert(name.replace('-', "_"), v);
        }
        if self.mode == Mode::Trace {
            settings.insert("trace_spp".into(), self.trace.spp.into());
            if self.trace.seed != 0 {
                settings.insert("trace_seed".into(), self.trace.seed.into());
            }
        }
        settings
    }
}

/// Every row, in table order.
pub fn all_rows() -> Vec<Row> {
    let layered = || Row::new("layered-pem", Mode::LayeredPem);
    let labelled = |label: &str| Row {
        label: label.into(),
        ..layered()
    };
    vec![
        Row::new("static-em", Mode::StaticEm),
        Row::new("sphere-pem", Mode::SpherePem),
        Row::new("sphere-pem nearest-sample", Mode::SpherePem).with(|p| p.blend = false),
        Row::new("sphere-pem uncompressed", Mode::SpherePem).with(|p| p.maps = Maps::Exr),
        layered(),
        labelled("layered-pem multipass").with(|p| p.compositing = Compositing::Multipass),
        labelled("layered-pem analytic-room").with(|p| p.room = RoomShading::Analytic),
        labelled("layered-pem nearest-sample").with(|p| p.blend = false),
        labelled("layered-pem bilinear-views").with(|p| p.view_blend = ViewBlend::Bilinear),
        labelled("layered-pem edge-filter").with(|p| p.edge_filter = true),
        labelled("layered-pem distant-only").with(|p| p.local_layer = false),
        labelled("layered-pem em128").with(|p| p.em_size = Some(128)),
        labelled("layered-pem em64").with(|p| p.em_size = Some(64)),
        labelled("layered-pem bilinear").with(|p| p.filtering = Filtering::Bilinear),
        labelled("layered-pem nearest-texel").with(|p| p.filtering = Filtering::Nearest),
        labelled("layered-pem spacing2").with(|p| p.spacing = 2),
        labelled("layered-pem spacing4").with(|p| p.spacing = 4),
        labelled("layered-pem spacing8").with(|p| p.spacing = 8),
        labelled("layered-pem uncompressed").with(|p| p.maps = Maps::Exr),
        Row::new("rem", Mode::Rem),
        Row::new("rem nearest-sample", Mode::Rem).with(|p| p.blend = false),
        Row::new("rem level1", Mode::Rem).with(|p| {
            p.rem_level = 1;
            p.rem_size = 128;
        }),
        Row::new("ptm", Mode::Ptm),
        Row::new("ptm nearest-sample", Mode::Ptm).with(|p| p.blend = false),
        trace_4spp(),
        reference_noise(),
    ]
}

/// A seed other than the references': traced rows share no samples with
/// the images they are scored against (the same seed would replay the
/// references' first samples and read high).
fn independent_seed() -> u64 {
    super::reference::REFERENCE_SEED + 1
}

/// The tracer at 4 spp: its speed and its noise.
fn trace_4spp() -> Row {
    Row {
        trace: TraceFrames {
            spp: 4,
            seed: independent_seed(),
        },
        ..Row::new("trace 4spp", Mode::Trace)
    }
}

/// [`REFERENCE_NOISE`]; its samples per pixel are set to the references'
/// when the eval runs.
fn reference_noise() -> Row {
    Row {
        trace: TraceFrames {
            spp: 16,
            seed: independent_seed(),
        },
        ..Row::new(REFERENCE_NOISE, Mode::Trace)
    }
}

/// The rows of a scene with a glass object: hybrid at τ = 3 (labelled
/// plainly, so the eval pictures it), 5 and 10 subpixels, hybrid from the
/// one traced shell (where the scene has per-sample shells, the
/// comparison), from the traced layers (where layered shells have
/// per-sample maps; elsewhere the same frames as `hybrid`), the static
/// refraction EM baseline and the tracer.
pub fn glass_rows() -> Vec<Row> {
    let mut rows: Vec<Row> = [3.0f32, 5.0, 10.0]
        .iter()
        .map(|&tau| {
            let label = match tau {
                3.0 => "hybrid".to_string(),
                _ => format!("hybrid tau{tau}"),
            };
            Row::new(&label, Mode::Hybrid).with(|p| p.tau = Some(tau))
        })
        .collect();
    rows.push(Row::new("hybrid traced-shell", Mode::Hybrid).with(|p| {
        p.tau = Some(3.0);
        p.traced_shell = true;
    }));
    rows.push(Row::new("hybrid traced-layers", Mode::Hybrid).with(|p| {
        p.tau = Some(3.0);
        p.traced_layers = true;
    }));
    rows.push(Row::new("static-em", Mode::StaticEm));
    rows.push(trace_4spp());
    rows.push(reference_noise());
    rows
}

/// The rows of `scene`: [`glass_rows`] when it has a glass object.
pub fn rows_for(scene: &inference::scene::Scene) -> Vec<Row> {
    if scene.objects.iter().any(|o| o.glass.is_some()) {
        glass_rows()
    } else {
        all_rows()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_have_unique_labels_and_replayable_flags() {
        let rows = all_rows();
        for (i, r) in rows.iter().enumerate() {
            assert!(rows[..i].iter().all(|o| o.label != r.label), "{}", r.label);
        }
        let spacing = rows
            .iter()
            .find(|r| r.label == "layered-pem spacing4")
            .expect("row");
        assert_eq!(spacing.flags(), "--mode layered-pem --spacing 4");
        let s = spacing.settings();
        assert_eq!(s["spacing"], serde_json::json!(4));
        assert_eq!(s["label"], serde_json::json!("layered-pem spacing4"));
        let nearest = rows
            .iter()
            .find(|r| r.label == "ptm nearest-sample")
            .expect("row");
        assert_eq!(nearest.flags(), "--mode ptm --no-blend");
        assert_eq!(nearest.settings()["no_blend"], serde_json::json!(true));
        let trace = rows.iter().find(|r| r.mode == Mode::Trace).expect("row");
        assert_eq!(trace.flags(), "--mode trace --trace-spp 4 --trace-seed 3");
    }

    #[test]
    fn glass_rows_carry_tau() {
        let rows = glass_rows();
        let taus: Vec<_> = rows.iter().filter_map(|r| r.pem.tau).collect();
        assert_eq!(taus, vec![3.0, 5.0, 10.0, 3.0, 3.0]);
        let traced = rows.iter().find(|r| r.pem.traced_shell).expect("row");
        assert_eq!(traced.flags(), "--mode hybrid --tau 3 --traced-shell");
        assert_eq!(traced.settings()["traced_shell"], serde_json::json!(true));
        let layers = rows.iter().find(|r| r.pem.traced_layers).expect("row");
        assert_eq!(layers.flags(), "--mode hybrid --tau 3 --traced-layers");
        assert_eq!(layers.settings()["traced_layers"], serde_json::json!(true));
        assert_eq!(rows[0].flags(), "--mode hybrid --tau 3");
        assert_eq!(rows[0].label, "hybrid");
        assert_eq!(rows[1].label, "hybrid tau5");
        assert_eq!(rows[0].settings()["tau"], serde_json::json!(3));
        assert!(rows.iter().any(|r| r.mode == Mode::StaticEm));
        assert!(rows.iter().any(|r| r.mode == Mode::Trace));
    }

    #[test]
    fn the_reference_noise_row_traces_another_seed_at_the_references_spp() {
        let references = super::super::reference::REFERENCE_SEED;
        for rows in [all_rows(), glass_rows()] {
            let noise = rows
                .into_iter()
                .find(|r| r.label == REFERENCE_NOISE)
                .expect("row")
                .against_references(64);
            assert_eq!(noise.mode, Mode::Trace);
            assert_eq!(noise.trace.spp, 64);
            assert_ne!(noise.trace.seed, references);
            let seed = noise.trace.seed;
            assert_eq!(
                noise.flags(),
                format!("--mode trace --trace-spp 64 --trace-seed {seed}")
            );
            assert_eq!(noise.settings()["trace_seed"], serde_json::json!(seed));
        }
        // Other rows keep their own samples per pixel; no traced row
        // shares the references' seed.
        let four = all_rows()
            .into_iter()
            .find(|r| r.label == "trace 4spp")
            .expect("row");
        assert_eq!(four.against_references(64).trace.spp, 4);
        for row in all_rows().into_iter().chain(glass_rows()) {
            if row.mode == Mode::Trace {
                assert_ne!(row.trace.seed, references, "{}", row.label);
            }
        }
    }
}

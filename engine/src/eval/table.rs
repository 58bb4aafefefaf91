//! `eval.json`, the speed/accuracy table (issue #5): one row per rendering
//! mode and settings, with accuracy against the traced reference at three
//! kinds of view and the time per frame; and its Markdown form for the README.
//!
//! The three kinds of view: `on` = orbit samples (on the manifold the maps
//! were inferred for), `between` = azimuths between samples, `above` = off
//! the orbit in elevation. Each score is the row's aggregate over the views
//! of that kind (the driver says which aggregate in its docs).

use super::metrics::PSNR_CAP_DB;
use super::relight::RelightReport;
use crate::util::files::write as write_atomically;
use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// The whole file: `{"rows": [...]}`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EvalTable {
    pub rows: Vec<EvalRow>,
    /// The `relight` rows: `engine relight`'s measurement, when selected.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relight: Option<RelightReport>,
}

/// One mode at one set of settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EvalRow {
    /// What renders the frame, e.g. `"pem"`, `"static_em"`.
    pub mode: String,
    /// The knobs of this row by name (EM resolution, layers, blending,
    /// compression rate, …): any JSON value. Sorted by name in the file.
    pub settings: BTreeMap<String, serde_json::Value>,
    /// PSNR in dB over the reflector's pixels (see
    /// [`super::metrics::masked_psnr`]: bounded to ±`PSNR_CAP_DB`).
    pub psnr_on_db: f64,
    pub psnr_between_db: f64,
    pub psnr_above_db: f64,
    /// Mean LDR-FLIP error over the reflector's pixels, 0 (identical) to 1
    /// (see [`super::metrics::masked_flip`]).
    pub flip_on: f64,
    pub flip_between: f64,
    pub flip_above: f64,
    /// Whole-frame scores, every pixel, display-referred (the 8-bit sRGB
    /// PNG: [`super::metrics::display_psnr`], FLIP over the whole frame),
    /// when measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub psnr_frame_on_db: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub psnr_frame_between_db: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub psnr_frame_above_db: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flip_frame_on: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flip_frame_between: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flip_frame_above: Option<f64>,
    /// Milliseconds per frame (the driver says whether median or mean).
    pub frame_ms: f64,
    /// 95th percentile of the frame times, when measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame_ms_p95: Option<f64>,
    /// How many views each kind's scores aggregate, when recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub views: Option<ViewCounts>,
    /// Bytes of maps this mode reads (on disk or uploaded), when known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map_bytes: Option<u64>,
    /// Viewpoint samples the maps hold (the row's sample budget), for
    /// modes that read per-sample maps.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<u32>,
    /// Shell layers a hybrid glass row reads (1: the room's box alone).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shell_layers: Option<u32>,
    /// Minutes those maps took to compile (traces, inference and encode,
    /// as the container's key record keeps them), when known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compile_minutes: Option<f64>,
    /// Scores at each elevation above the plane (the `*_above` fields are
    /// the first's).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub above: Vec<AboveScore>,
    /// The PSNRs with the references' own noise taken out, when the eval
    /// measured it (`super::noise`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise_free: Option<super::noise::NoiseFree>,
}

/// One elevation's views above the plane: mean PSNR and FLIP over the
/// reflector, and over the whole frame as the PNG shows it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AboveScore {
    pub elevation_deg: f32,
    pub psnr_db: f64,
    pub flip: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub psnr_frame_db: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flip_frame: Option<f64>,
}

/// Views behind each kind of score.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewCounts {
    pub on: u32,
    pub between: u32,
    pub above: u32,
}

impl EvalRow {
    /// The row's numbers by JSON field name, for checks and messages.
    fn numbers(&self) -> [(&'static str, Option<f64>); 15] {
        [
            ("psnr_on_db", Some(self.psnr_on_db)),
            ("psnr_between_db", Some(self.psnr_between_db)),
            ("psnr_above_db", Some(self.psnr_above_db)),
            ("flip_on", Some(self.flip_on)),
            ("flip_between", Some(self.flip_between)),
            ("flip_above", Some(self.flip_above)),
            ("psnr_frame_on_db", self.psnr_frame_on_db),
            ("psnr_frame_between_db", self.psnr_frame_between_db),
            ("psnr_frame_above_db", self.psnr_frame_above_db),
            ("flip_frame_on", self.flip_frame_on),
            ("flip_frame_between", self.flip_frame_between),
            ("flip_frame_above", self.flip_frame_above),
            ("frame_ms", Some(self.frame_ms)),
            ("frame_ms_p95", self.frame_ms_p95),
            ("compile_minutes", self.compile_minutes),
        ]
    }
}

impl EvalTable {
    /// An error naming the first row and field that JSON cannot hold or that
    /// is out of its range: every number finite, FLIP in [0, 1], times ≥ 0.
    pub fn validate(&self) -> Result<()> {
        for (i, row) in self.rows.iter().enumerate() {
            for (field, value) in row.numbers() {
                let Some(v) = value else { continue };
                let range = match field {
                    f if f.starts_with("flip") => Some((0.0, 1.0)),
                    f if f.starts_with("frame_ms") || f == "compile_minutes" => {
                        Some((0.0, f64::INFINITY))
                    }
                    _ => None,
                };
                let ok = v.is_finite() && range.is_none_or(|(lo, hi)| (lo..=hi).contains(&v));
                if !ok {
                    let expected = match range {
                        Some((lo, hi)) if hi.is_finite() => format!("a number in [{lo}, {hi}]"),
                        Some((lo, _)) => format!("a finite number ≥ {lo}"),
                        None => "a finite number".to_owned(),
                    };
                    bail!(
                        "eval row {i} (mode {:?}): {field} is {v}, expected {expected}",
                        row.mode
                    );
                }
            }
        }
        if let Some(r) = &self.relight {
            r.validate()?;
        }
        Ok(())
    }

    /// Writes the table as pretty JSON to `path`, atomically, after
    /// [`EvalTable::validate`].
    pub fn write(&self, path: &Path) -> Result<()> {
        self.validate()
            .with_context(|| format!("not writing {}", path.display()))?;
        let mut text = serde_json::to_string_pretty(self)
            .with_context(|| format!("serialising {}", path.display()))?;
        text.push('\n');
        write_atomically(path, text.as_bytes())
    }

    /// Reads a table written by [`EvalTable::write`] (and validates it).
    pub fn read(path: &Path) -> Result<EvalTable> {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        let table: EvalTable = serde_json::from_str(&text).with_context(|| {
            format!(
                "{}: expected an eval table {{\"rows\": [{{\"mode\", \"settings\", \"psnr_on_db\", …}}]}}",
                path.display()
            )
        })?;
        table
            .validate()
            .with_context(|| format!("{}", path.display()))?;
        Ok(table)
    }

    /// PSNR and FLIP of every row at each elevation above the plane (empty
    /// when no row has more than one elevation).
    pub fn above_markdown(&self) -> String {
        let Some(first) = self.rows.iter().find(|r| r.above.len() > 1) else {
            return String::new();
        };
        let elevations: Vec<f32> = first.above.iter().map(|a| a.elevation_deg).collect();
        let mut out = String::from("\n| label |");
        for e in &elevations {
            let _ = write!(out, " PSNR +{e}° (dB) | FLIP +{e}° | frame +{e}° (dB) |");
        }
        out += "\n|---|";
        out += &"--:|--:|--:|".repeat(elevations.len());
        out += "\n";
        for row in &self.rows {
            let label = row
                .settings
                .get("label")
                .and_then(|v| v.as_str())
                .unwrap_or(&row.mode);
            let _ = write!(out, "| {} |", cell(label));
            for e in &elevations {
                match row.above.iter().find(|a| a.elevation_deg == *e) {
                    Some(a) => {
                        let frame = a.psnr_frame_db.map_or("—".to_owned(), psnr_cell);
                        let _ =
                            write!(out, " {} | {:.4} | {frame} |", psnr_cell(a.psnr_db), a.flip);
                    }
                    None => out += " — | — | — |",
                }
            }
            out += "\n";
        }
        out
    }

    /// A GitHub Markdown table, one line per row in order: mode, settings as
    /// `name=value` pairs, PSNR (dB, 2 decimals; `≥ 100` at the cap), FLIP
    /// (4 decimals), ms/frame (2 decimals), the bytes of the maps played,
    /// their samples and compile minutes (`—` where none are counted).
    /// Ends with a newline.
    pub fn to_markdown(&self) -> String {
        let mut out = String::from(
            "| mode | settings | PSNR on (dB) | PSNR between (dB) | PSNR above (dB) \
             | FLIP on | FLIP between | FLIP above | ms/frame | map bytes | samples \
             | compile min |\n\
             |---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n",
        );
        for row in &self.rows {
            let settings = if row.settings.is_empty() {
                "—".to_owned()
            } else {
                row.settings
                    .iter()
                    .map(|(k, v)| match v {
                        serde_json::Value::String(s) => format!("{k}={s}"),
                        other => format!("{k}={other}"),
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {} | {:.4} | {:.4} | {:.4} | {:.2} | {} | {} | {} |",
                cell(&row.mode),
                cell(&settings),
                psnr_cell(row.psnr_on_db),
                psnr_cell(row.psnr_between_db),
                psnr_cell(row.psnr_above_db),
                row.flip_on,
                row.flip_between,
                row.flip_above,
                row.frame_ms,
                row.map_bytes
                    .map_or_else(|| "—".to_owned(), |b| b.to_string()),
                row.samples
                    .map_or_else(|| "—".to_owned(), |n| n.to_string()),
                row.compile_minutes
                    .map_or_else(|| "—".to_owned(), |m| format!("{m:.1}")),
            );
        }
        out
    }
}

fn psnr_cell(db: f64) -> String {
    if db >= PSNR_CAP_DB {
        format!("≥ {PSNR_CAP_DB:.0}")
    } else {
        format!("{db:.2}")
    }
}

/// Text safe inside a Markdown table cell: pipes escaped, line breaks as spaces.
fn cell(text: &str) -> String {
    text.replace('|', "\\|").replace(['\n', '\r'], " ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn table_of(rows: Vec<EvalRow>) -> EvalTable {
        EvalTable {
            rows,
            relight: None,
        }
    }

    fn row(mode: &str) -> EvalRow {
        EvalRow {
            mode: mode.to_owned(),
            settings: BTreeMap::from([
                ("em_resolution".to_owned(), json!(256)),
                ("blend".to_owned(), json!(true)),
                ("filter".to_owned(), json!("trilinear")),
            ]),
            psnr_on_db: 31.25,
            psnr_between_db: 29.5,
            psnr_above_db: 24.126,
            flip_on: 0.0625,
            flip_between: 0.07,
            flip_above: 0.1,
            psnr_frame_on_db: None,
            psnr_frame_between_db: None,
            psnr_frame_above_db: None,
            flip_frame_on: None,
            flip_frame_between: None,
            flip_frame_above: None,
            frame_ms: 3.5,
            frame_ms_p95: None,
            views: None,
            map_bytes: None,
            samples: None,
            shell_layers: None,
            compile_minutes: None,
            above: Vec::new(),
            noise_free: None,
        }
    }

    #[test]
    fn json_has_the_issue_shape() -> Result<()> {
        let table = table_of(vec![row("pem")]);
        let value = serde_json::to_value(&table)?;
        assert_eq!(
            value,
            json!({"rows": [{
                "mode": "pem",
                "settings": {"blend": true, "em_resolution": 256, "filter": "trilinear"},
                "psnr_on_db": 31.25,
                "psnr_between_db": 29.5,
                "psnr_above_db": 24.126,
                "flip_on": 0.0625,
                "flip_between": 0.07,
                "flip_above": 0.1,
                "frame_ms": 3.5
            }]})
        );
        // Whole-frame scores, when measured, sit beside the reflector's.
        let mut framed = row("pem");
        framed.psnr_frame_above_db = Some(30.5);
        framed.flip_frame_above = Some(0.08);
        let value = serde_json::to_value(&framed)?;
        assert_eq!(value["psnr_frame_above_db"], json!(30.5));
        assert_eq!(value["flip_frame_above"], json!(0.08));
        assert!(value.get("flip_frame_on").is_none());
        framed.flip_frame_on = Some(1.5);
        let e = table_of(vec![framed])
            .validate()
            .err()
            .map(|e| e.to_string());
        assert!(
            e.as_ref().is_some_and(|e| e.contains("flip_frame_on")),
            "{e:?}"
        );
        Ok(())
    }

    #[test]
    fn extras_appear_when_set_and_round_trip() -> Result<()> {
        let mut r = row("static_em");
        r.frame_ms_p95 = Some(4.0);
        r.views = Some(ViewCounts {
            on: 10,
            between: 9,
            above: 4,
        });
        r.map_bytes = Some(1 << 20);
        r.samples = Some(23);
        r.compile_minutes = Some(12.5);
        let table = table_of(vec![row("pem"), r]);
        let value = serde_json::to_value(&table)?;
        assert_eq!(
            value["rows"][1]["views"],
            json!({"on": 10, "between": 9, "above": 4})
        );
        assert_eq!(value["rows"][1]["frame_ms_p95"], json!(4.0));
        assert_eq!(value["rows"][1]["map_bytes"], json!(1 << 20));
        assert_eq!(value["rows"][1]["samples"], json!(23));
        assert_eq!(value["rows"][1]["compile_minutes"], json!(12.5));
        assert!(value["rows"][0].get("samples").is_none());
        assert!(value["rows"][0].get("compile_minutes").is_none());
        let markdown = table.to_markdown();
        assert!(markdown.contains("| samples | compile min |"), "{markdown}");
        assert!(markdown.contains("| 23 | 12.5 |"), "{markdown}");

        let dir = tempfile::tempdir()?;
        let path = dir.path().join("eval.json");
        table.write(&path)?;
        assert_eq!(EvalTable::read(&path)?, table);
        Ok(())
    }

    #[test]
    fn non_finite_or_out_of_range_numbers_are_refused() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let path = dir.path().join("eval.json");
        let mut bad = row("pem");
        bad.psnr_between_db = f64::INFINITY;
        let table = table_of(vec![bad]);
        let e = table.write(&path).err().map(|e| format!("{e:#}"));
        assert!(
            e.as_ref()
                .is_some_and(|e| e.contains("psnr_between_db") && e.contains("eval.json")),
            "{e:?}"
        );
        assert!(!path.exists());
        let mut bad = row("pem");
        bad.flip_above = 1.5;
        assert!(table_of(vec![bad]).validate().is_err());
        let mut bad = row("pem");
        bad.frame_ms_p95 = Some(f64::NAN);
        assert!(table_of(vec![bad]).validate().is_err());
        let mut bad = row("pem");
        bad.compile_minutes = Some(-1.0);
        let e = table_of(vec![bad])
            .validate()
            .err()
            .map(|e| format!("{e:#}"));
        assert!(e.is_some_and(|e| e.contains("compile_minutes")));
        Ok(())
    }

    #[test]
    fn reading_a_wrong_file_names_it() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let path = dir.path().join("eval.json");
        std::fs::write(&path, r#"{"rows": [{"mode": "pem"}]}"#)?;
        let e = EvalTable::read(&path).err().map(|e| format!("{e:#}"));
        assert!(e.is_some_and(|e| e.contains("eval.json") && e.contains("psnr")));
        Ok(())
    }

    #[test]
    fn markdown_has_one_line_per_row() {
        let mut capped = row("a|b");
        capped.psnr_on_db = PSNR_CAP_DB;
        capped.settings.clear();
        let table = table_of(vec![row("pem"), capped]);
        let md = table.to_markdown();
        let lines: Vec<&str> = md.lines().collect();
        assert_eq!(lines.len(), 4);
        assert_eq!(
            lines[2],
            "| pem | blend=true, em_resolution=256, filter=trilinear | 31.25 | 29.50 | 24.13 \
             | 0.0625 | 0.0700 | 0.1000 | 3.50 | — | — | — |"
        );
        assert!(lines[3].starts_with("| a\\|b | — | ≥ 100 | "));
        // Same number of cells on every line (escaped pipes are not separators).
        let cells = |l: &str| l.replace("\\|", "").matches('|').count();
        assert!(lines.iter().all(|l| cells(l) == 13), "{md}");
    }
}

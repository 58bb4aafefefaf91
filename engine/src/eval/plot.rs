//! XY charts as PNG (plotters): scatter and line series with a text label
//! per point, axis labels, title, legend, optional log x axis.
//!
//! Text uses DejaVu Sans embedded from `assets/fonts/` (plotters' `ab_glyph`
//! feature), so charts render the same on a machine without any system font.
//! plotters draws into an RGB buffer; `image` encodes it and the file is
//! written atomically.

use crate::util::files::write as write_atomically;
use anyhow::{Context, Result, anyhow, bail};
use image::ImageEncoder;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

/// DejaVu Sans 2.37 (Debian's fonts-dejavu-core); licence beside it.
const FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");
/// The family plotters asks for by default, so every text uses [`FONT`].
pub(super) const FAMILY: &str = "sans-serif";
const MAX_SIDE: u32 = 8192;
const MIN_SIDE: u32 = 200;

/// Tableau 10: distinct, colour-blind-friendlier than plotters' palettes.
pub(super) const COLORS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// One set of points in one colour.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Series {
    /// Shown in the legend.
    pub name: String,
    pub points: Vec<(f64, f64)>,
    /// Text beside each point: empty for none, else one per point.
    pub labels: Vec<String>,
    /// Join the points with a line in the given order (else markers only).
    pub connect: bool,
}

/// Corner of the plot that holds the legend.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LegendPosition {
    UpperLeft,
    UpperRight,
    LowerLeft,
    #[default]
    LowerRight,
    /// No legend.
    Hidden,
}

/// Everything a chart shows.
#[derive(Clone, Debug, PartialEq)]
pub struct ChartSpec {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// Pixels, width × height (each 200 to 8192).
    pub size: (u32, u32),
    /// Logarithmic x axis (every x must then be > 0).
    pub log_x: bool,
    pub legend: LegendPosition,
    /// Room right of the rightmost point, as a fraction of the x span
    /// (point labels; a legend beside the points). Linear x axes only.
    pub x_margin_right: f64,
    pub series: Vec<Series>,
}

impl ChartSpec {
    /// A 1024×640 chart with a linear x axis, the legend lower right, no series.
    pub fn new(title: &str, x_label: &str, y_label: &str) -> ChartSpec {
        ChartSpec {
            title: title.to_owned(),
            x_label: x_label.to_owned(),
            y_label: y_label.to_owned(),
            size: (1024, 640),
            log_x: false,
            legend: LegendPosition::default(),
            x_margin_right: 0.18,
            series: Vec::new(),
        }
    }

    /// An error naming the first series and point that cannot be drawn.
    pub fn validate(&self) -> Result<()> {
        let (w, h) = self.size;
        if !(MIN_SIDE..=MAX_SIDE).contains(&w) || !(MIN_SIDE..=MAX_SIDE).contains(&h) {
            bail!("chart size {w}x{h}: expected {MIN_SIDE} to {MAX_SIDE} pixels each way");
        }
        for s in &self.series {
            if !s.labels.is_empty() && s.labels.len() != s.points.len() {
                bail!(
                    "series {:?}: {} labels for {} points, expected one per point or none",
                    s.name,
                    s.labels.len(),
                    s.points.len()
                );
            }
            for (i, &(x, y)) in s.points.iter().enumerate() {
                if !(x.is_finite() && y.is_finite()) {
                    bail!(
                        "series {:?} point {i}: ({x}, {y}), expected finite x and y",
                        s.name
                    );
                }
                if self.log_x && x <= 0.0 {
                    bail!(
                        "series {:?} point {i}: x = {x}, expected x > 0 on a log x axis",
                        s.name
                    );
                }
            }
        }
        Ok(())
    }
}

/// Draws `spec` and writes it to `path` as an RGB PNG of `spec.size`
/// (atomically: a temporary file renamed into place). Axis ranges cover every
/// point with a margin; a chart without points gets unit ranges.
pub fn xy_chart(path: &Path, spec: &ChartSpec) -> Result<()> {
    spec.validate()
        .with_context(|| format!("not writing {}", path.display()))?;
    register_font()?;
    let (w, h) = spec.size;
    let mut rgb = vec![255u8; w as usize * h as usize * 3];
    let xs = || {
        spec.series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0))
    };
    let ys = spec
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1));
    let y = padded_linear(ys, 0.08);
    let drawn = if spec.log_x {
        draw(&mut rgb, spec, padded_log(xs()).log_scale(), y)
    } else {
        draw(
            &mut rgb,
            spec,
            padded_linear_sides(xs(), 0.05, spec.x_margin_right),
            y,
        )
    };
    drawn.with_context(|| format!("drawing {}", path.display()))?;
    encode_png(path, &rgb, (w, h))
}

/// Encodes an RGB buffer of `(w, h)` as PNG into `path`, atomically.
pub(super) fn encode_png(path: &Path, rgb: &[u8], (w, h): (u32, u32)) -> Result<()> {
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(rgb, w, h, image::ExtendedColorType::Rgb8)
        .with_context(|| format!("encoding {}", path.display()))?;
    write_atomically(path, &png)
}

/// Registers [`FONT`] with plotters once per process.
pub(super) fn register_font() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err(anyhow!(
            "the embedded font assets/fonts/DejaVuSans.ttf is not a font plotters can read"
        ))
    }
}

fn draw<X>(rgb: &mut [u8], spec: &ChartSpec, x: X, y: Range<f64>) -> Result<()>
where
    X: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
{
    let root = BitMapBackend::with_buffer(rgb, spec.size).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(&spec.title, (FAMILY, 24))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(64)
        .build_cartesian_2d(x, y)?;
    chart
        .configure_mesh()
        .x_desc(&spec.x_label)
        .y_desc(&spec.y_label)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 16))
        .light_line_style(RGBColor(235, 235, 235))
        .max_light_lines(4)
        .draw()?;
    let label_style = TextStyle::from((FAMILY, 13).into_font()).color(&BLACK);
    for (i, s) in spec.series.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        if s.connect {
            chart.draw_series(LineSeries::new(
                s.points.iter().copied(),
                color.stroke_width(2),
            ))?;
        }
        let markers = chart.draw_series(s.points.iter().enumerate().map(|(k, &p)| {
            let text = s.labels.get(k).cloned().unwrap_or_default();
            EmptyElement::at(p)
                + Circle::new((0, 0), 4, color.filled())
                + Text::new(text, (7, -16), label_style.clone())
        }))?;
        markers
            .label(s.name.clone())
            .legend(move |(x, y)| Circle::new((x + 8, y), 4, color.filled()));
    }
    let position = match spec.legend {
        LegendPosition::UpperLeft => Some(SeriesLabelPosition::UpperLeft),
        LegendPosition::UpperRight => Some(SeriesLabelPosition::UpperRight),
        LegendPosition::LowerLeft => Some(SeriesLabelPosition::LowerLeft),
        LegendPosition::LowerRight => Some(SeriesLabelPosition::LowerRight),
        LegendPosition::Hidden => None,
    };
    if let (Some(position), false) = (position, spec.series.is_empty()) {
        chart
            .configure_series_labels()
            .position(position)
            .label_font((FAMILY, 14))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
    }
    root.present()?;
    Ok(())
}

/// `[min, max]` of `values` widened by `margin` of the span each side (a
/// single value by 10 % of itself, or 1); `0..1` when there are none.
fn padded_linear(values: impl Iterator<Item = f64>, margin: f64) -> Range<f64> {
    padded_linear_sides(values, margin, margin)
}

/// As [`padded_linear`] with its own margin on the high side (room for
/// point labels, which are drawn to the right of their points).
fn padded_linear_sides(values: impl Iterator<Item = f64>, low: f64, high: f64) -> Range<f64> {
    let Some((lo, hi)) = min_max(values) else {
        return 0.0..1.0;
    };
    let span = if hi > lo {
        hi - lo
    } else if lo != 0.0 {
        lo.abs()
    } else {
        10.0
    };
    (lo - span * low)..(hi + span * high)
}

/// As [`padded_linear`] for positive values, by factors: `1..10` when none.
fn padded_log(values: impl Iterator<Item = f64>) -> Range<f64> {
    let Some((lo, hi)) = min_max(values) else {
        return 1.0..10.0;
    };
    let factor = if hi > lo { (hi / lo).powf(0.05) } else { 2.0 };
    (lo / factor)..(hi * factor)
}

fn min_max(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    values.fold(None, |acc, v| match acc {
        None => Some((v, v)),
        Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
    })
}

/// A tick label: up to 3 significant decimals without trailing zeros,
/// scientific notation outside [10⁻², 10⁵).
fn tick(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-2..1e5).contains(&a) {
        return format!("{v:.1e}");
    }
    let decimals = if a >= 100.0 {
        0
    } else if a >= 10.0 {
        1
    } else if a >= 1.0 {
        2
    } else {
        3
    };
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(log_x: bool) -> ChartSpec {
        let mut spec = ChartSpec::new(
            "PSNR against frame time",
            "frame time (ms)",
            "PSNR on the teapot (dB)",
        );
        spec.size = (640, 400);
        spec.log_x = log_x;
        spec.series = vec![
            Series {
                name: "pem".into(),
                points: vec![(0.8, 28.0), (1.6, 31.5), (3.2, 33.0)],
                labels: vec!["64²".into(), "128²".into(), "256²".into()],
                connect: true,
            },
            Series {
                name: "static EM".into(),
                points: vec![(0.5, 21.0)],
                labels: vec![],
                connect: false,
            },
        ];
        spec
    }

    fn decode(path: &Path) -> Result<image::RgbImage> {
        Ok(image::open(path)
            .with_context(|| format!("decoding {}", path.display()))?
            .to_rgb8())
    }

    fn non_white(img: &image::RgbImage) -> usize {
        img.pixels().filter(|p| p.0 != [255, 255, 255]).count()
    }

    #[test]
    fn writes_a_png_of_the_requested_size_that_is_not_blank() -> Result<()> {
        let dir = tempfile::tempdir()?;
        for log_x in [false, true] {
            let path = dir.path().join(format!("chart_{log_x}.png"));
            xy_chart(&path, &spec(log_x))?;
            let img = decode(&path)?;
            assert_eq!(img.dimensions(), (640, 400));
            let n = non_white(&img);
            assert!(n > 2000 && n < 640 * 400 / 2, "{n} non-white pixels");
            // Series colours are there.
            assert!(img.pixels().any(|p| p.0 == [31, 119, 180]));
            assert!(img.pixels().any(|p| p.0 == [255, 127, 14]));
        }
        let names: Vec<_> = std::fs::read_dir(dir.path())?.collect::<Result<_, _>>()?;
        assert_eq!(names.len(), 2, "no temporary file left");
        Ok(())
    }

    #[test]
    fn text_is_drawn_with_the_embedded_font() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let with = dir.path().join("with.png");
        let without = dir.path().join("without.png");
        let mut plain = spec(false);
        xy_chart(&with, &plain)?;
        plain.title.clear();
        plain.series[0].labels.clear();
        xy_chart(&without, &plain)?;
        // Title and point labels add dark pixels (anti-aliased glyphs).
        let dark = |img: &image::RgbImage| {
            img.pixels()
                .filter(|p| p.0[0] < 100 && p.0[1] < 100 && p.0[2] < 100)
                .count()
        };
        let (a, b) = (dark(&decode(&with)?), dark(&decode(&without)?));
        assert!(a > b + 300, "{a} dark pixels with text, {b} without");
        Ok(())
    }

    #[test]
    fn an_empty_chart_still_draws() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let path = dir.path().join("empty.png");
        let mut s = spec(true);
        s.series.clear();
        xy_chart(&path, &s)?;
        assert_eq!(decode(&path)?.dimensions(), (640, 400));
        Ok(())
    }

    #[test]
    fn bad_specs_are_errors_naming_the_problem() {
        let dir = tempfile::tempdir().expect("tempdir");
        let missing = dir.path().join("missing-dir/chart.png");
        let path = missing.as_path();
        let mut s = spec(true);
        s.series[1].points[0].0 = 0.0;
        let e = xy_chart(path, &s).err().map(|e| format!("{e:#}"));
        assert!(e.is_some_and(|e| e.contains("static EM") && e.contains("x > 0")));
        let mut s = spec(false);
        s.series[0].labels.pop();
        assert!(s.validate().is_err());
        let mut s = spec(false);
        s.series[0].points[1].1 = f64::NAN;
        assert!(s.validate().is_err());
        let mut s = spec(false);
        s.size = (10, 10);
        assert!(s.validate().is_err());
        // A folder that does not exist: an error naming the file, no panic.
        let e = xy_chart(path, &spec(false)).err().map(|e| format!("{e:#}"));
        assert!(e.is_some_and(|e| e.contains("chart.png")));
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(2.5), "2.5");
        assert_eq!(tick(31.26), "31.3");
        assert_eq!(tick(120.0), "120");
        assert_eq!(tick(0.125), "0.125");
        assert_eq!(tick(-3.0), "-3");
        assert_eq!(tick(1e-4), "1.0e-4");
    }
}

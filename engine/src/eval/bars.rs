//! Horizontal stacked bars as PNG (plotters): one bar per row, its
//! segments left to right, each segment name in one colour across every
//! bar and once in the legend. `engine bench` draws where each variant's
//! frame goes with it.

use super::plot::{COLORS, FAMILY, encode_png, register_font};
use anyhow::{Context, Result, bail};
use plotters::coord::ranged1d::SegmentValue;
use plotters::prelude::*;
use std::path::Path;

/// One bar: its label (left of it) and its segments, `(name, value)`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bar {
    pub label: String,
    pub segments: Vec<(String, f64)>,
}

/// A chart of bars, the first on top.
#[derive(Clone, Debug, PartialEq)]
pub struct BarChart {
    pub title: String,
    /// The value axis' description.
    pub x_label: String,
    pub bars: Vec<Bar>,
}

impl BarChart {
    /// An error naming the first bar and segment that cannot be drawn.
    pub fn validate(&self) -> Result<()> {
        if self.bars.is_empty() {
            bail!("no bars to draw");
        }
        for b in &self.bars {
            for (name, v) in &b.segments {
                if !(v.is_finite() && *v >= 0.0) {
                    bail!(
                        "bar {:?} segment {name:?}: {v}, expected a finite value ≥ 0",
                        b.label
                    );
                }
            }
        }
        Ok(())
    }

    /// Segment names in order of first appearance: the legend's entries
    /// and, by position, their colours.
    fn names(&self) -> Vec<&str> {
        let mut names: Vec<&str> = Vec::new();
        for (name, _) in self.bars.iter().flat_map(|b| &b.segments) {
            if !names.contains(&name.as_str()) {
                names.push(name);
            }
        }
        names
    }
}

/// Draws `chart` and writes it to `path` as an RGB PNG (atomically). The
/// height follows the number of bars.
pub fn stacked_bars(path: &Path, chart: &BarChart) -> Result<()> {
    chart
        .validate()
        .with_context(|| format!("not writing {}", path.display()))?;
    register_font()?;
    let names = chart.names();
    let size = (1200, (120 + 34 * chart.bars.len() as u32).max(260));
    let mut rgb = vec![255u8; size.0 as usize * size.1 as usize * 3];
    draw(&mut rgb, size, chart, &names).with_context(|| format!("drawing {}", path.display()))?;
    encode_png(path, &rgb, size)
}

fn draw(rgb: &mut [u8], size: (u32, u32), chart: &BarChart, names: &[&str]) -> Result<()> {
    let n = chart.bars.len() as i32;
    let total = |b: &Bar| b.segments.iter().map(|(_, v)| v).sum::<f64>();
    let widest = chart.bars.iter().map(total).fold(0.0, f64::max);
    // Room on the right for the legend.
    let x_max = if widest > 0.0 { widest * 1.3 } else { 1.0 };
    let label_w = chart.bars.iter().map(|b| b.label.len()).max().unwrap_or(0) as u32;
    let root = BitMapBackend::with_buffer(rgb, size).into_drawing_area();
    root.fill(&WHITE)?;
    let mut c = ChartBuilder::on(&root)
        .caption(&chart.title, (FAMILY, 22))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(24 + 8 * label_w)
        .build_cartesian_2d(0.0..x_max, (0..n).into_segmented())?;
    // Bar i is drawn at y = n − 1 − i, so the first bar is on top.
    let label_of = |v: &SegmentValue<i32>| match v {
        SegmentValue::CenterOf(y) if (0..n).contains(y) => {
            chart.bars[(n - 1 - y) as usize].label.clone()
        }
        _ => String::new(),
    };
    c.configure_mesh()
        .x_desc(&chart.x_label)
        .y_label_formatter(&label_of)
        .y_labels(chart.bars.len())
        .disable_y_mesh()
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 16))
        .light_line_style(RGBColor(235, 235, 235))
        .max_light_lines(4)
        .draw()?;
    let color = |name: &str| palette(names.iter().position(|n| *n == name).unwrap_or(0));
    for (i, bar) in chart.bars.iter().enumerate() {
        let y = n - 1 - i as i32;
        let mut x = 0.0;
        let rects = bar.segments.iter().map(|(name, v)| {
            let mut r = Rectangle::new(
                [
                    (x, SegmentValue::Exact(y)),
                    (x + v, SegmentValue::Exact(y + 1)),
                ],
                color(name).filled(),
            );
            r.set_margin(4, 4, 0, 0); // a gap between bars
            x += v;
            r
        });
        c.draw_series(rects)?;
    }
    for &name in names {
        let col = color(name);
        c.draw_series(std::iter::empty::<Rectangle<(f64, SegmentValue<i32>)>>())?
            .label(name)
            .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 12, y + 6)], col.filled()));
    }
    c.configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FAMILY, 13))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

/// Colour `i`: the ten of [`COLORS`], then the same ten half-way to white
/// (a bench row can have a dozen passes), then around again.
fn palette(i: usize) -> RGBColor {
    let RGBColor(r, g, b) = COLORS[i % COLORS.len()];
    if (i / COLORS.len()) % 2 == 0 {
        RGBColor(r, g, b)
    } else {
        let light = |c: u8| ((u16::from(c) + 255) / 2) as u8;
        RGBColor(light(r), light(g), light(b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bar(label: &str, segments: &[(&str, f64)]) -> Bar {
        Bar {
            label: label.into(),
            segments: segments.iter().map(|(n, v)| (n.to_string(), *v)).collect(),
        }
    }

    #[test]
    fn bars_are_drawn_with_one_colour_per_segment_name() {
        let chart = BarChart {
            title: "where the frame goes".into(),
            x_label: "ms".into(),
            bars: vec![
                bar("bare", &[("bare", 8.0), ("outside", 1.8)]),
                bar(
                    "default",
                    &[("gbuffer", 4.7), ("room", 4.0), ("outside", 2.2)],
                ),
            ],
        };
        assert_eq!(chart.names(), ["bare", "outside", "gbuffer", "room"]);
        assert_ne!(palette(3), palette(13), "twenty distinct colours");
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("bars.png");
        stacked_bars(&path, &chart).expect("drawn");
        let img = image::open(&path).expect("a PNG").to_rgb8();
        assert_eq!(img.width(), 1200);
        // Every segment name's colour is on the picture.
        for i in 0..4 {
            let RGBColor(r, g, b) = palette(i);
            assert!(img.pixels().any(|p| p.0 == [r, g, b]), "colour {i} missing");
        }
    }

    #[test]
    fn bad_values_and_no_bars_are_errors_naming_them() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("bars.png");
        let mut chart = BarChart {
            title: String::new(),
            x_label: String::new(),
            bars: vec![bar("row", &[("pass", f64::NAN)])],
        };
        let e = stacked_bars(&path, &chart).expect_err("NaN");
        assert!(format!("{e:#}").contains("\"pass\""), "{e:#}");
        chart.bars = vec![bar("row", &[("pass", -1.0)])];
        assert!(stacked_bars(&path, &chart).is_err());
        chart.bars.clear();
        assert!(stacked_bars(&path, &chart).is_err());
        assert!(!path.exists());
    }
}

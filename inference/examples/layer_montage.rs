//! Side-by-side picture of a traced sample's layers for the README:
//! `cargo run --release -p inference --example layer_montage -- IN.exr OUT.png [LAYER...]`.
//! Each panel is the layer tone-mapped like the PNG beside the EXR, halved in size;
//! single-channel layers are shown grey, RGBA layers over black.

use inference::trace::output::{read_exr, tone_map};
use std::process::ExitCode;

const DEFAULT: [&str; 6] = [
    "beauty",
    "teapot.mask",
    "teapot.fresnel",
    "teapot.specular_distant",
    "teapot.specular_local",
    "floor.diffuse",
];
const COLUMNS: usize = 3;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(input), Some(output)) = (args.first(), args.get(1)) else {
        eprintln!("usage: layer_montage IN.exr OUT.png [LAYER...]");
        return ExitCode::FAILURE;
    };
    let wanted: Vec<&str> = if args.len() > 2 {
        args[2..].iter().map(String::as_str).collect()
    } else {
        DEFAULT.to_vec()
    };
    match montage(input, output, &wanted) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn montage(input: &str, output: &str, wanted: &[&str]) -> Result<(), String> {
    let layers = read_exr(input.as_ref()).map_err(|e| e.to_string())?;
    let header = exr::meta::MetaData::read_from_file(input, false).map_err(|e| e.to_string())?;
    let size = header.headers[0].layer_size;
    let (w, h) = (size.0, size.1);
    let (pw, ph) = (w / 2, h / 2);
    let rows = wanted.len().div_ceil(COLUMNS);
    let mut img = image::RgbImage::new((pw * COLUMNS) as u32, (ph * rows) as u32);
    for (i, name) in wanted.iter().enumerate() {
        let (_, channels) = layers
            .iter()
            .find(|(n, _)| n == name)
            .ok_or_else(|| format!("{input}: no layer {name}"))?;
        let get = |c: &str| channels.iter().find(|(n, _)| n == c).map(|(_, v)| v);
        let (r, g, b) = match (get("R"), get("G"), get("B"), get("Y")) {
            (Some(r), Some(g), Some(b), _) => (r, g, b),
            (_, _, _, Some(y)) => (y, y, y),
            _ => return Err(format!("{name}: neither RGB nor Y")),
        };
        let alpha = get("A");
        let (ox, oy) = ((i % COLUMNS) * pw, (i / COLUMNS) * ph);
        for y in 0..ph {
            for x in 0..pw {
                let mut rgb = [0.0f32; 3];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let k = (2 * y + dy) * w + 2 * x + dx;
                    let a = alpha.map_or(1.0, |a| a[k]);
                    rgb[0] += 0.25 * r[k] * a;
                    rgb[1] += 0.25 * g[k] * a;
                    rgb[2] += 0.25 * b[k] * a;
                }
                img.put_pixel(
                    (ox + x) as u32,
                    (oy + y) as u32,
                    image::Rgb(rgb.map(tone_map)),
                );
            }
        }
    }
    img.save(output).map_err(|e| format!("{output}: {e}"))
}

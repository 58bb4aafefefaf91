//! The command line's value parsers: each refuses what the engine cannot
//! use before any work starts, naming the value and what was expected.

/// Parses `WIDTHxHEIGHT`, each 1..=8192.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    pair(
        s,
        (8192, 8192),
        "WIDTHxHEIGHT (each 1 to 8192, e.g. 640x480)",
    )
}

/// Parses a light grid `RINGSxAZIMUTHS` (rings 1..=64, azimuths 1..=128,
/// as the relighting grid allows).
pub fn parse_grid(s: &str) -> Result<(u32, u32), String> {
    pair(
        s,
        (64, 128),
        "RINGSxAZIMUTHS (rings 1 to 64, azimuths 1 to 128, e.g. 8x16)",
    )
}

/// Two counts `AxB`, each from 1 to its `max`, else "expected {expected}".
fn pair(s: &str, max: (u32, u32), expected: &str) -> Result<(u32, u32), String> {
    let parsed = s.split_once(['x', 'X']).and_then(|(a, b)| {
        let a: u32 = a.trim().parse().ok()?;
        let b: u32 = b.trim().parse().ok()?;
        ((1..=max.0).contains(&a) && (1..=max.1).contains(&b)).then_some((a, b))
    });
    parsed.ok_or_else(|| format!("expected {expected}, got {s:?}"))
}

/// A worker thread count, 1 to 256 (more only queues work on a machine's
/// cores and costs a stack each).
pub fn parse_threads(s: &str) -> Result<usize, String> {
    number(
        s,
        |t: usize| (1..=256).contains(&t),
        "a thread count from 1 to 256",
    )
}

/// A number that parses and passes `ok`, else "expected {expected}".
fn number<T: std::str::FromStr + Copy>(
    s: &str,
    ok: impl Fn(T) -> bool,
    expected: &str,
) -> Result<T, String> {
    match s.trim().parse::<T>() {
        Ok(v) if ok(v) => Ok(v),
        _ => Err(format!("expected {expected}, got {s:?}")),
    }
}

/// An angle in degrees: finite.
pub fn parse_degrees(s: &str) -> Result<f32, String> {
    number(s, f32::is_finite, "an angle in degrees")
}

/// An elevation above the orbit plane: strictly between −90° and 90° (at
/// ±90° the eye stands over the look-at point and the view has no up;
/// past it the eye crosses the pole).
pub fn parse_elevation(s: &str) -> Result<f32, String> {
    number(
        s,
        |d: f32| d.abs() < 90.0,
        "an elevation in degrees strictly between -90 and 90",
    )
}

/// A PSNR in dB: finite.
pub fn parse_db(s: &str) -> Result<f64, String> {
    number(s, f64::is_finite, "a finite PSNR in dB (e.g. 42)")
}

/// A regularization weight: finite and not negative.
pub fn parse_weight(s: &str) -> Result<f32, String> {
    number(
        s,
        |w: f32| w.is_finite() && w >= 0.0,
        "a finite weight >= 0",
    )
}

/// A tessellation threshold τ in subpixels.
pub fn parse_tau(s: &str) -> Result<f32, String> {
    let range = inference::scene::glass::GLASS_TAU;
    number(s, |t| range.contains(&t), &format!("{range:?} subpixels"))
}

/// A compression ratio above 1 and at most 100,000 (`engine::compile::encode::check_ratio`).
pub fn parse_ratio(s: &str) -> Result<f64, String> {
    use engine::compile::encode::{RATIO_EXPECTED, check_ratio};
    number(s, |r: f64| check_ratio(r).is_ok(), RATIO_EXPECTED)
}

/// `bilinear` or `triangles` (`--view-blend`).
pub fn parse_view_blend(s: &str) -> Result<inference::scene::ViewBlend, String> {
    s.parse()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_reject() {
        assert_eq!(parse_size("640x480"), Ok((640, 480)));
        for bad in ["640", "0x480", "640x", "axb", "9000x10", "-1x5"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn grids_parse_and_reject_naming_a_grid() {
        assert_eq!(parse_grid("8x16"), Ok((8, 16)));
        assert_eq!(parse_grid("64X128"), Ok((64, 128)));
        for bad in ["0x0", "65x1", "1x129", "8", "8x", "axb", "-1x5"] {
            let e = parse_grid(bad).expect_err(bad);
            assert!(e.contains("RINGSxAZIMUTHS") && e.contains(bad), "{e}");
        }
    }

    #[test]
    fn view_blends_parse_and_name_what_is_expected() {
        use inference::scene::ViewBlend;
        assert_eq!(parse_view_blend("triangles"), Ok(ViewBlend::Triangles));
        assert_eq!(parse_view_blend("bilinear"), Ok(ViewBlend::Bilinear));
        let e = parse_view_blend("cubic").expect_err("unknown");
        assert!(e.contains("cubic") && e.contains("`triangles`"), "{e}");
    }
}

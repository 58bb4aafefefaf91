use super::*;
use crate::entropy::{CostMeter, Reader, Writer};

#[test]
fn image_round_trip_at_fine_step() {
    let (w, h, ch) = (19, 13, 4);
    let planar: Vec<f32> = (0..w * h * ch)
        .map(|i| {
            ((i % w) as f32 * 0.3).sin() * 4.0
                + (i / (w * h)) as f32
                + ((i * 7919) % 13) as f32 * 0.01
        })
        .collect();
    let mut dct = Dct8::default();
    let img = CoefImage::new(&mut dct, &planar, w, h, ch);
    let step = step_of(100);
    let mut wtr = Writer::default();
    let sse = encode_image(&mut wtr, &mut Contexts::default(), &img, step);
    let mut meter = CostMeter::default();
    let sse2 = encode_image(&mut meter, &mut Contexts::default(), &img, step);
    assert_eq!(sse, sse2);
    let bytes = wtr.finish().unwrap();
    assert!((bytes.len() as f64 * 8.0 - meter.bits).abs() < 0.05 * meter.bits + 96.0);
    let mut out = vec![0.0; w * h * ch];
    let mut r = Reader::new(&bytes).unwrap();
    decode_image_add(
        &mut r,
        &mut Contexts::default(),
        &dct,
        w,
        h,
        ch,
        step,
        &mut out,
    )
    .unwrap();
    let mut real_sse = 0.0;
    for c in 0..ch {
        for i in 0..w * h {
            let e = (out[c * w * h + i] - planar[c * w * h + i]) as f64;
            real_sse += CHANNEL_SSE_WEIGHT[c] * e * e;
        }
    }
    // Padding makes the DCT-domain SSE cover more texels than the crop.
    assert!(real_sse <= sse * 1.01 + 1e-9, "{real_sse} > {sse}");
    let max_err = out
        .iter()
        .zip(&planar)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max);
    assert!(max_err < 64.0 * step, "max error {max_err}");
}

#[test]
fn step_index_is_monotone() {
    assert_eq!(step_of(128), 1.0);
    assert!(step_of(idx_at_least(0.3)) >= 0.3);
    assert!(step_of(idx_at_least(0.3) - 1) < 0.3);
}

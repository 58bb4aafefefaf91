//! Decode time per leaf EM (256×256×6 with the full MIP chain, RGBA) and
//! encode ratio/PSNR points on synthetic data.
//!
//! `cargo bench -p codec --bench codec`

use std::hint::black_box;
use std::time::Instant;

use codec::report::{ReportOptions, report};
use codec::synth::{SynthSpec, scene};
use codec::{Container, DecodeCache, EncodeOptions, Lifetimes, ParamGrid, Target, encode};
use criterion::{Criterion, criterion_group, criterion_main};
use half::f16;

const SIZE: u32 = 256;
const SAMPLES: u32 = 8;

fn setup(ratio: f64) -> (codec::EncodeInput, Container) {
    let input = scene(&SynthSpec::cube(1, 1, ParamGrid::one_d(SAMPLES), SIZE));
    let t = Instant::now();
    let (bytes, rep) =
        encode(&input, Target::Ratio(ratio), &EncodeOptions::default()).expect("encode");
    eprintln!(
        "encode {SIZE}x{SIZE}x6+MIPs, {SAMPLES} samples at {ratio}:1 -> {} bytes (ratio {:.1}) in {:.2} s",
        rep.bytes,
        rep.ratio,
        t.elapsed().as_secs_f64()
    );
    (input, Container::from_bytes(bytes).expect("container"))
}

fn decode(c: &mut Criterion) {
    for ratio in [384.0, 768.0] {
        let (input, container) = setup(ratio);
        let rep = report(
            &container,
            &input,
            &ReportOptions {
                jpeg_baseline: false,
                ffmpeg_baseline: false,
                videos: Vec::new(),
            },
        )
        .expect("report");
        eprintln!(
            "point: ratio {:.1}  psnr {:.2} dB  bytes {}",
            rep.ratio, rep.psnr_db, rep.bytes
        );
        let texels = input.textures[0].layout.texels();
        let mut out = vec![f16::ZERO; texels * 4];
        let mut out32 = vec![0.0f32; texels * 4];

        c.bench_function(&format!("decode_leaf_em_cold_{ratio}"), |b| {
            b.iter(|| {
                let mut cache = DecodeCache::default();
                cache
                    .decode_leaf_all(&container, 0, 0, [3, 0], &mut out)
                    .expect("decode");
                black_box(&out);
            })
        });
        // Leaf level decoded every time, coarser levels resident: a playback
        // step inside a block.
        let mut cache = DecodeCache::new(Lifetimes { a: 1, b: 1000 });
        let mut s = 0;
        c.bench_function(&format!("decode_leaf_em_leaf_level_{ratio}"), |b| {
            b.iter(|| {
                cache
                    .decode_leaf_all(&container, 0, 0, [s, 0], &mut out)
                    .expect("decode");
                cache.end_frame();
                cache.end_frame();
                s = (s + 1) % SAMPLES;
                black_box(&out);
            })
        });
        let mut warm = DecodeCache::default();
        c.bench_function(&format!("decode_leaf_em_resident_f16_{ratio}"), |b| {
            b.iter(|| {
                warm.decode_leaf_all(&container, 0, 0, [3, 0], &mut out)
                    .expect("decode");
                black_box(&out);
            })
        });
        c.bench_function(&format!("decode_leaf_em_resident_f32_{ratio}"), |b| {
            b.iter(|| {
                warm.decode_leaf_all(&container, 0, 0, [3, 0], &mut out32)
                    .expect("decode");
                black_box(&out32);
            })
        });
    }
}

fn encode_bench(c: &mut Criterion) {
    let input = scene(&SynthSpec::cube(1, 1, ParamGrid::one_d(SAMPLES), 64));
    let mut g = c.benchmark_group("encode");
    g.sample_size(10);
    g.bench_function("encode_64x64x6_8samples_384", |b| {
        b.iter(|| {
            black_box(
                encode(&input, Target::Ratio(384.0), &EncodeOptions::default()).expect("encode"),
            )
        })
    });
    g.finish();
}

criterion_group!(benches, decode, encode_bench);
criterion_main!(benches);

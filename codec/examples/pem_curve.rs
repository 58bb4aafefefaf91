//! Ratio against texture PSNR on the real PEM (`engine infer --all`
//! output), the codec at several ratios against x264, x265 and AV1 at the
//! codec's bytes (MPEG-texture, `codec::report`), plus decode time.
//!
//! `cargo run --release -p codec --example pem_curve -- --dir /work/data/teapot/infer
//!  [--samples N] [--layers 0,1,2] [--ratios 100,200,400,800,1600] [--x264] [--x265] [--av1]
//!  [--memo FILE] [--save DIR] [--texels] [--alpha-cap A] [--rd-points N]`
//!
//! `--memo FILE` keeps the baselines' (CRF → bytes, PSNR) measurements as
//! JSON between runs on the same input; `--save DIR` writes the containers.

#[path = "pem/load.rs"]
mod load;

use std::path::PathBuf;
use std::time::Instant;

use codec::encode::Weighting;
use codec::report::{CrfMemo, ReportOptions, VideoCodec, mpeg_texture_baselines_memo, report};
use codec::{
    Container, DecodeCache, EncodeInput, EncodeOptions, PsnrAccum, Target, encode_targets,
};

struct Args {
    dir: PathBuf,
    object: String,
    size: u32,
    samples: u32,
    layers: Vec<usize>,
    ratios: Vec<f64>,
    codecs: Vec<VideoCodec>,
    memo: Option<PathBuf>,
    save: Option<PathBuf>,
    opts: EncodeOptions,
}

fn parse() -> Result<Args, Box<dyn std::error::Error>> {
    let mut a = Args {
        dir: PathBuf::from("/work/data/teapot/infer"),
        object: "teapot".into(),
        size: 256,
        samples: 100,
        layers: vec![0, 1, 2],
        ratios: vec![100.0, 200.0, 400.0, 800.0, 1600.0],
        codecs: Vec::new(),
        memo: None,
        save: None,
        opts: EncodeOptions::default(),
    };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut it = args.iter();
    let list = |s: &str| s.split(',').map(str::to_string).collect::<Vec<_>>();
    while let Some(k) = it.next() {
        let mut v = || it.next().ok_or(format!("{k} needs a value"));
        match k.as_str() {
            "--dir" => a.dir = v()?.into(),
            "--object" => a.object = v()?.clone(),
            "--size" => a.size = v()?.parse()?,
            "--samples" => a.samples = v()?.parse()?,
            "--layers" => {
                a.layers = list(v()?)
                    .iter()
                    .map(|s| s.parse())
                    .collect::<Result<_, _>>()?
            }
            "--ratios" => {
                a.ratios = list(v()?)
                    .iter()
                    .map(|s| s.parse())
                    .collect::<Result<_, _>>()?
            }
            "--x264" => a.codecs.push(VideoCodec::X264),
            "--x265" => a.codecs.push(VideoCodec::X265),
            "--av1" => a.codecs.push(VideoCodec::Av1),
            "--memo" => a.memo = Some(v()?.into()),
            "--save" => a.save = Some(v()?.into()),
            "--texels" => a.opts.weighting = Weighting::Texels,
            "--alpha-cap" => a.opts.alpha_cap = v()?.parse()?,
            "--rd-points" => a.opts.rd_points = v()?.parse()?,
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    Ok(a)
}

fn load_memo(path: &Option<PathBuf>) -> Vec<(String, u32, u64, f64)> {
    path.as_ref()
        .and_then(|p| std::fs::read(p).ok())
        .and_then(|b| serde_json::from_slice(&b).ok())
        .unwrap_or_default()
}

/// Texture PSNR of the container with each decoded alpha replaced by the
/// reference's (the MPEG baselines do not code alpha).
fn psnr_alpha_exact(c: &Container, input: &EncodeInput) -> codec::Result<f64> {
    let mut acc = PsnrAccum::default();
    let mut cache = DecodeCache::default();
    for t in &input.textures {
        let mut out = vec![0.0f32; t.layout.texels() * 4];
        for s in 0..t.grid.n0 {
            cache.decode_leaf_all(c, t.id.object, t.id.layer, [s, 0], &mut out)?;
            cache.end_frame();
            let reference = t.sample(s as usize);
            if t.layout.channels == 4 {
                for (o, r) in out.chunks_exact_mut(4).zip(reference.chunks_exact(4)) {
                    o[3] = r[3];
                }
            }
            acc.add(reference, t.layout.channels as usize, &out, 4);
        }
    }
    Ok(acc.psnr_db())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a = parse()?;
    let t0 = Instant::now();
    let input = load::load(&a.dir, &a.object, a.size, a.samples, &a.layers)?;
    eprintln!(
        "loaded {} samples x {} textures ({:.1} MB raw) in {:.1}s",
        a.samples,
        input.textures.len(),
        input.raw_bytes() as f64 / 1e6,
        t0.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    let targets: Vec<Target> = a.ratios.iter().map(|&r| Target::Ratio(r)).collect();
    let encoded = encode_targets(&input, &targets, &a.opts)?;
    eprintln!(
        "encoded {} targets in {:.1}s",
        targets.len(),
        t.elapsed().as_secs_f64()
    );
    let mut bytes_list = Vec::new();
    println!("| target | ratio | PSNR dB | bytes | decode ms p50 |");
    println!("|---|---|---|---|---|");
    for (r, (bytes, _)) in a.ratios.iter().zip(encoded) {
        if let Some(dir) = &a.save {
            std::fs::create_dir_all(dir)?;
            std::fs::write(dir.join(format!("pem_{r}.ptxc")), &bytes)?;
        }
        let c = Container::from_bytes(bytes)?;
        let opts = ReportOptions {
            jpeg_baseline: false,
            ffmpeg_baseline: false,
            videos: Vec::new(),
        };
        let rep = report(&c, &input, &opts)?;
        println!(
            "| {r} | {:.1} | {:.2} | {} | {:.3} |",
            rep.ratio, rep.psnr_db, rep.bytes, rep.decode_ms_median
        );
        eprintln!(
            "    texture PSNR with alpha taken as exact, as the MPEG baselines do: {:.2} dB",
            psnr_alpha_exact(&c, &input)?
        );
        let per: Vec<String> = rep
            .textures
            .iter()
            .map(|t| format!("{:.2}", t.psnr_db))
            .collect();
        eprintln!("    per texture PSNR {}", per.join(" / "));
        bytes_list.push(rep.bytes);
    }
    baselines(&a, &input, &bytes_list)
}

/// The MPEG baselines at the codec's bytes, one table per encoder.
fn baselines(
    a: &Args,
    input: &EncodeInput,
    bytes_list: &[u64],
) -> Result<(), Box<dyn std::error::Error>> {
    let mut memo_all = load_memo(&a.memo);
    for codec in &a.codecs {
        let mut memo: CrfMemo = memo_all
            .iter()
            .filter(|m| m.0 == codec.name())
            .map(|m| (m.1, (m.2, m.3)))
            .collect();
        let base = mpeg_texture_baselines_memo(*codec, input, bytes_list, &mut memo, &mut |m| {
            eprintln!("    {m}")
        })?;
        memo_all.retain(|m| m.0 != codec.name());
        memo_all.extend(
            memo.iter()
                .map(|(&k, &(b, p))| (codec.name().to_string(), k, b, p)),
        );
        if let Some(p) = &a.memo {
            std::fs::write(p, serde_json::to_vec(&memo_all)?)?;
        }
        println!(
            "| {} at the codec's bytes | ratio | PSNR dB | bytes | note |",
            codec.name()
        );
        println!("|---|---|---|---|---|");
        for (r, b) in a.ratios.iter().zip(base) {
            println!(
                "| {r} | {:.1} | {:.2} | {} | {} |",
                b.ratio,
                b.psnr_db,
                b.bytes,
                b.note.unwrap_or_default()
            );
        }
    }
    Ok(())
}

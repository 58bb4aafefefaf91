//! Leaf decode time the way `codec-report` measures it (playback along the
//! parameter path, default cache lifetimes, f16 output, an untimed pass
//! first), per texture — wall time and this thread's CPU time, which a
//! shared machine disturbs less — plus a hash of every decoded texel (f32 and f16
//! outputs) so two builds can be checked for identical results.
//!
//! `cargo run --release -p codec --example decode_timing -- [CONTAINER] [--reps N] [--hash] [--texture I] [--no-ahead]`
//!
//! After each leaf, `warm_ahead` decodes the next samples' coarse levels
//! (untimed in the leaf's time, as playback's worker runs it after handing
//! the map over; its own time is printed apart); `--no-ahead` leaves it out.
//!
//! Without a container it encodes the benchmark's synthetic leaf EM
//! (256×256×6 + MIPs, RGBA, 8 samples, 384:1) first.

use std::time::Instant;

use codec::synth::{SynthSpec, scene};
use codec::{Container, DecodeCache, EncodeOptions, ParamGrid, Target, TextureInfo, encode};
use half::f16;

fn fnv(h: &mut u64, bytes: impl IntoIterator<Item = u8>) {
    for b in bytes {
        *h ^= b as u64;
        *h = h.wrapping_mul(0x100_0000_01b3);
    }
}

/// This thread's CPU time in ms.
fn cpu_ms() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec for the call to fill.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    t.tv_sec as f64 * 1e3 + t.tv_nsec as f64 * 1e-6
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// What the command line asks for.
struct Args {
    reps: usize,
    hash: bool,
    path: Option<String>,
    only: Option<usize>,
    ahead: bool,
}

fn parse_args() -> Result<Args, Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut parsed = Args {
        reps: 1,
        hash: false,
        path: None,
        only: None,
        ahead: true,
    };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--reps" => parsed.reps = it.next().ok_or("--reps N")?.parse()?,
            "--hash" => parsed.hash = true,
            "--no-ahead" => parsed.ahead = false,
            "--texture" => parsed.only = Some(it.next().ok_or("--texture I")?.parse::<usize>()?),
            p => parsed.path = Some(p.to_string()),
        }
    }
    Ok(parsed)
}

/// The container at `path`, or the benchmark's synthetic leaf EM encoded.
fn open_or_synthesise(path: Option<&str>) -> Result<Container, Box<dyn std::error::Error>> {
    Ok(match path {
        Some(p) => Container::open(p.as_ref())?,
        None => {
            let input = scene(&SynthSpec::cube(1, 1, ParamGrid::one_d(8), 256));
            let (bytes, _) = encode(&input, Target::Ratio(384.0), &EncodeOptions::default())?;
            Container::from_bytes(bytes)?
        }
    })
}

/// One texture's decode times (wall and thread CPU, ms) over `reps` timed
/// passes along the parameter path, after an untimed one.
struct Timed {
    wall: Vec<f64>,
    cpu: Vec<f64>,
    /// Thread CPU time of each leaf's `warm_ahead` after it (ms).
    warm: Vec<f64>,
    peak_images: usize,
    peak_bytes: usize,
}

fn time_texture(
    c: &Container,
    t: &TextureInfo,
    reps: usize,
    ahead: bool,
    out: &mut [f16],
) -> codec::Result<Timed> {
    let mut cache = DecodeCache::default();
    let (mut times, mut cpu, mut warm) = (Vec::new(), Vec::new(), Vec::new());
    let (mut peak_images, mut peak_bytes) = (0, 0);
    for pass in 0..=reps {
        for s1 in 0..t.grid.n1 {
            for s0 in 0..t.grid.n0 {
                let (start, c0) = (Instant::now(), cpu_ms());
                cache.decode_leaf_all(c, t.id.object, t.id.layer, [s0, s1], out)?;
                let ms = start.elapsed().as_secs_f64() * 1e3;
                let c1 = cpu_ms();
                if ahead {
                    cache.warm_ahead(c, t.id.object, t.id.layer)?;
                    if pass > 0 {
                        warm.push(cpu_ms() - c1);
                    }
                }
                cache.end_frame();
                if pass > 0 {
                    times.push(ms);
                    cpu.push(c1 - c0);
                }
            }
        }
        peak_images = peak_images.max(cache.stats().resident_images);
        peak_bytes = peak_bytes.max(cache.stats().resident_bytes);
        cache.clear();
    }
    Ok(Timed {
        wall: times,
        cpu,
        warm,
        peak_images,
        peak_bytes,
    })
}

/// FNV hashes of every decoded texel of `t` along the parameter path, as
/// f32 and as f16 (`out` is the f16 output buffer).
fn hash_texture(c: &Container, t: &TextureInfo, out: &mut [f16]) -> codec::Result<(u64, u64)> {
    let mut h32 = 0xcbf2_9ce4_8422_2325u64;
    let mut h16 = h32;
    let mut out32 = vec![0.0f32; out.len()];
    let mut c32 = DecodeCache::default();
    let mut c16 = DecodeCache::default();
    for s1 in 0..t.grid.n1 {
        for s0 in 0..t.grid.n0 {
            let s = [s0, s1];
            c32.decode_leaf_all(c, t.id.object, t.id.layer, s, &mut out32)?;
            c16.decode_leaf_all(c, t.id.object, t.id.layer, s, out)?;
            c32.end_frame();
            c16.end_frame();
            fnv(
                &mut h32,
                out32.iter().flat_map(|v| v.to_bits().to_le_bytes()),
            );
            fnv(&mut h16, out.iter().flat_map(|v| v.to_bits().to_le_bytes()));
        }
    }
    Ok((h32, h16))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = parse_args()?;
    let c = open_or_synthesise(args.path.as_deref())?;
    let (mut all, mut all_cpu, mut all_warm) = (Vec::new(), Vec::new(), Vec::new());
    for (ti, t) in c.textures().iter().enumerate() {
        if args.only.is_some_and(|o| o != ti) {
            continue;
        }
        let mut out = vec![f16::ZERO; t.layout.texels() * 4];
        let Timed {
            wall: mut times,
            mut cpu,
            warm,
            peak_images,
            peak_bytes,
        } = time_texture(&c, t, args.reps, args.ahead, &mut out)?;
        all.extend_from_slice(&times);
        all_cpu.extend_from_slice(&cpu);
        all_warm.extend_from_slice(&warm);
        let l = t.layout;
        print!(
            "texture ({}, {}) {}x{}x{} ch {} mips {}: median {:.3} ms wall, {:.3} ms cpu (mean {:.3}) over {} decodes; cache at the end {} images, {:.1} MB",
            t.id.object,
            t.id.layer,
            l.width,
            l.height,
            l.faces,
            l.channels,
            l.mips,
            median(&mut times),
            median(&mut cpu),
            mean(&cpu),
            times.len(),
            peak_images,
            peak_bytes as f64 / 1e6
        );
        if args.hash {
            let (h32, h16) = hash_texture(&c, t, &mut out)?;
            print!("  hash f32 {h32:016x} f16 {h16:016x}");
        }
        println!();
    }
    println!(
        "all: median {:.3} ms wall, {:.3} ms cpu, p95 {:.3} ms wall, {:.3} ms cpu over {} decodes",
        median(&mut all),
        median(&mut all_cpu),
        codec::report::quantile(&all, 0.95),
        codec::report::quantile(&all_cpu, 0.95),
        all.len()
    );
    if !all_warm.is_empty() {
        println!(
            "warming ahead after each leaf (cpu, untimed above): mean {:.3} ms, p95 {:.3} ms",
            mean(&all_warm),
            codec::report::quantile(&all_warm, 0.95)
        );
    }
    Ok(())
}

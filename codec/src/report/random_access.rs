//! Random access as a measured feature: the time and the bytes it takes to
//! show one arbitrary sample (every texture of it) from cold. The pyramid
//! opens the container, reads that sample's blocks and decodes its levels;
//! a video decodes from its GOP's I-frame up to the sample's frame.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Instant;

use serde::Serialize;

use super::ffmpeg::{VideoCodec, encode_video, err};
use super::mpeg_texture::{GOP, video_streams};
use crate::container::Container;
use crate::decode::DecodeCache;
use crate::error::Result;
use crate::input::EncodeInput;

/// One codec's random access, medians over the measured samples.
#[derive(Clone, Debug, Serialize)]
pub struct RandomAccess {
    pub name: String,
    /// Time to show one sample, every texture of it, from cold.
    pub ms: f64,
    /// Bytes read for it (header and index included for the pyramid).
    pub bytes_read: u64,
    /// How many samples the medians pool.
    pub samples: usize,
    pub note: String,
}

/// About `count` distinct sample indices spread over `0..n`, at varying
/// offsets inside blocks of 8 (so neither codec is measured only at its
/// cheapest place); deterministic.
pub fn spread_samples(n: usize, count: usize) -> Vec<usize> {
    let count = count.min(n);
    let mut s: Vec<usize> = (0..count).map(|i| (i * n / count + i) % n).collect();
    s.sort_unstable();
    s.dedup();
    s
}

/// The pyramid: for each sample a fresh [`Container::open`] (header and
/// index read) and emptied decode caches (nothing of any sample decoded or
/// read; their memory stays allocated, as in a running player — the video
/// is timed with its decoder open too), then every texture's leaf at that
/// sample decoded (all faces and MIPs, f16), the textures dealt over
/// `threads` threads by size ([`deal_by_size`]). One untimed access first
/// allocates that memory. The file's pages may sit in the OS cache.
pub fn pyramid_random_access(
    path: &Path,
    samples: &[usize],
    threads: usize,
) -> Result<RandomAccess> {
    let threads = threads.max(1);
    let probe = Container::open(path)?;
    let mut outs: Vec<Vec<half::f16>> = probe
        .textures()
        .iter()
        .map(|t| vec![half::f16::ZERO; t.layout.texels() * 4])
        .collect();
    let mut caches: Vec<DecodeCache> = (0..threads).map(|_| DecodeCache::default()).collect();
    let (mut times, mut bytes) = (Vec::new(), Vec::new());
    for (i, &s) in samples.first().into_iter().chain(samples).enumerate() {
        let start = Instant::now();
        let c = Container::open(path)?;
        caches.iter_mut().for_each(DecodeCache::clear);
        let textures: Vec<_> = c.textures().iter().zip(&mut outs).collect();
        let chunks = deal_by_size(textures, threads, |(t, _)| {
            t.layout.texels() * t.layout.channels as usize
        });
        std::thread::scope(|scope| -> Result<()> {
            let c = &c;
            let workers: Vec<_> = chunks
                .into_iter()
                .zip(caches.iter_mut())
                .map(|(chunk, cache)| scope.spawn(move || decode_sample(c, cache, chunk, s)))
                .collect();
            for w in workers {
                w.join()
                    .map_err(|_| err("a decode thread panicked".into()))??;
            }
            Ok(())
        })?;
        if i > 0 {
            times.push(start.elapsed().as_secs_f64() * 1e3);
            bytes.push(c.bytes_read());
        }
    }
    Ok(RandomAccess {
        name: if threads == 1 {
            "pyramid".into()
        } else {
            format!("pyramid, {threads} threads")
        },
        ms: median(&mut times),
        bytes_read: median_u64(&mut bytes),
        samples: samples.len(),
        note: format!(
            "fresh open (header, index) and emptied decode caches per sample; every texture's leaf, all faces and MIPs, to f16; textures dealt over {threads} thread(s) by size"
        ),
    })
}

/// Deals `items` over at most `threads` chunks, largest `work` first onto
/// the chunk with the least work so far (longest-processing-time first):
/// the cube maps then decode side by side instead of on one thread.
fn deal_by_size<T>(mut items: Vec<T>, threads: usize, work: impl Fn(&T) -> usize) -> Vec<Vec<T>> {
    items.sort_by_key(|t| std::cmp::Reverse(work(t)));
    let mut chunks: Vec<(usize, Vec<T>)> = (0..threads.max(1)).map(|_| (0, Vec::new())).collect();
    for item in items {
        if let Some(least) = chunks.iter_mut().min_by_key(|(w, _)| *w) {
            least.0 += work(&item);
            least.1.push(item);
        }
    }
    chunks
        .into_iter()
        .map(|(_, c)| c)
        .filter(|c| !c.is_empty())
        .collect()
}

/// Decodes sample `s` of each texture in `chunk` into its buffer.
fn decode_sample(
    c: &Container,
    cache: &mut DecodeCache,
    chunk: Vec<(&crate::container::TextureInfo, &mut Vec<half::f16>)>,
    s: usize,
) -> Result<()> {
    for (t, out) in chunk {
        if s >= t.grid.len() {
            continue;
        }
        let n0 = t.grid.n0 as usize;
        let sample = [(s % n0) as u32, (s / n0) as u32];
        cache.decode_leaf_all(c, t.id.object, t.id.layer, sample, out)?;
    }
    Ok(())
}

/// A video along the parameter path (the `mpeg-texture` streams, one per
/// texture, at `crf`): per sample, the frames from its GOP's I-frame to it
/// (decode order) times the stream's measured per-frame decode time, and
/// those packets' bytes. The per-frame time is ffmpeg's marginal decode
/// time over the whole stream (process start and probing excluded, its
/// default threads), which favours the video: an I-frame costs more than
/// the average frame.
pub fn video_random_access(
    codec: VideoCodec,
    reference: &EncodeInput,
    crf: u32,
    samples: &[usize],
) -> Result<RandomAccess> {
    let scratch = super::scratch::Scratch::new("codec-access", codec.name())?;
    video_access_in(codec, reference, crf, samples, scratch.path())
}

fn video_access_in(
    codec: VideoCodec,
    reference: &EncodeInput,
    crf: u32,
    samples: &[usize],
    dir: &Path,
) -> Result<RandomAccess> {
    let mut ms = vec![0.0; samples.len()];
    let mut bytes = vec![0u64; samples.len()];
    for (i, st) in video_streams(reference)?.iter().enumerate() {
        let mp4 = dir.join(format!("t{i}.mp4"));
        encode_video(codec, &st.frames, st.w, st.h, crf, GOP, dir, &mp4)?;
        let packets = parse_packets(&probe_packets(&mp4)?)?;
        let per_frame = per_frame_decode_ms(&mp4, st.frames.len())?;
        for (j, &s) in samples.iter().enumerate() {
            let Some(pos) = st.order.iter().position(|&o| o == s) else {
                continue;
            };
            let (frames, b) = frames_to_show(&packets, pos)
                .ok_or_else(|| err(format!("{}: no packet for frame {pos}", mp4.display())))?;
            ms[j] += frames as f64 * per_frame;
            bytes[j] += b;
        }
    }
    Ok(RandomAccess {
        name: codec.baseline_name().into(),
        ms: median(&mut ms),
        bytes_read: median_u64(&mut bytes),
        samples: samples.len(),
        note: format!(
            "{} crf {crf}, GOP {GOP}: frames from the I-frame to the sample (decode order) x measured marginal decode time per frame; bytes of those packets",
            codec.name()
        ),
    })
}

/// One coded frame, in decode order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Packet {
    /// Presentation index (rank of its timestamp).
    pub frame: usize,
    pub bytes: u64,
    pub key: bool,
}

/// ffprobe's `pts,size,flags` lines (decode order) as packets; the frame
/// index is the rank of the timestamp, so edit-list offsets do not matter.
pub fn parse_packets(csv: &str) -> Result<Vec<Packet>> {
    let mut rows = Vec::new();
    for (n, line) in csv
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
    {
        let f: Vec<&str> = line.trim().split(',').collect();
        let bad = || {
            err(format!(
                "ffprobe line {}: expected pts,size,flags, got {line:?}",
                n + 1
            ))
        };
        let [pts, size, flags] = f[..] else {
            return Err(bad());
        };
        let pts: i64 = pts.parse().map_err(|_| bad())?;
        let size: u64 = size.parse().map_err(|_| bad())?;
        rows.push((pts, size, flags.starts_with('K')));
    }
    let mut sorted: Vec<i64> = rows.iter().map(|r| r.0).collect();
    sorted.sort_unstable();
    Ok(rows
        .iter()
        .map(|&(pts, bytes, key)| Packet {
            frame: sorted.partition_point(|&p| p < pts),
            bytes,
            key,
        })
        .collect())
}

/// Packets to decode to show frame `pos`: from the last key packet at or
/// before its packet through it, in decode order; (count, bytes).
pub fn frames_to_show(packets: &[Packet], pos: usize) -> Option<(usize, u64)> {
    let end = packets.iter().position(|p| p.frame == pos)?;
    let start = packets[..=end].iter().rposition(|p| p.key)?;
    let run = &packets[start..=end];
    Some((run.len(), run.iter().map(|p| p.bytes).sum()))
}

fn probe_packets(mp4: &Path) -> Result<String> {
    let out = Command::new("ffprobe")
        .args(["-v", "error", "-select_streams", "v:0"])
        .args(["-show_entries", "packet=pts,size,flags", "-of", "csv=p=0"])
        .arg(mp4)
        .output()
        .map_err(|e| err(format!("ffprobe: {e}")))?;
    if !out.status.success() {
        return Err(err(format!("ffprobe {}: {}", mp4.display(), out.status)));
    }
    String::from_utf8(out.stdout).map_err(|e| err(format!("ffprobe output: {e}")))
}

/// Marginal decode time per frame: (all `n` frames − the first alone) /
/// (n − 1), each the median of three ffmpeg runs.
fn per_frame_decode_ms(mp4: &Path, n: usize) -> Result<f64> {
    if n < 2 {
        return Err(err("random access needs at least two frames".into()));
    }
    let run = |frames: usize| -> Result<f64> {
        let mut t = Vec::new();
        for _ in 0..3 {
            let start = Instant::now();
            let st = Command::new("ffmpeg")
                .args(["-v", "error", "-i"])
                .arg(mp4)
                .args(["-frames:v", &frames.to_string(), "-f", "null", "-"])
                .stdout(Stdio::null())
                .status()
                .map_err(|e| err(format!("ffmpeg: {e}")))?;
            if !st.success() {
                return Err(err(format!("decoding {}: {st}", mp4.display())));
            }
            t.push(start.elapsed().as_secs_f64() * 1e3);
        }
        Ok(median(&mut t))
    };
    let one = run(1)?;
    let all = run(n)?;
    Ok(((all - one) / (n - 1) as f64).max(0.0))
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

fn median_u64(v: &mut [u64]) -> u64 {
    v.sort_unstable();
    v.get(v.len() / 2).copied().unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn textures_are_dealt_largest_first_onto_the_least_loaded_thread() {
        // The teapot's three: distant RGB and local RGBA cube maps, a small PTM.
        let work = |&(_, w): &(char, usize)| w;
        let chunks = deal_by_size(vec![('d', 300), ('l', 400), ('p', 50)], 2, work);
        let names: Vec<Vec<char>> = chunks
            .iter()
            .map(|c| c.iter().map(|t| t.0).collect())
            .collect();
        assert_eq!(names, [vec!['l'], vec!['d', 'p']]);
        // More threads than textures: one each, no empty chunk.
        assert_eq!(deal_by_size(vec![('a', 1), ('b', 2)], 4, work).len(), 2);
        // One thread: everything, largest first.
        let one = deal_by_size(vec![('a', 1), ('b', 2)], 1, work);
        assert_eq!(one, [vec![('b', 2), ('a', 1)]]);
    }

    #[test]
    fn samples_are_spread_distinct_and_at_every_offset_of_a_block() {
        let s = spread_samples(100, 16);
        assert_eq!(s.len(), 16);
        assert!(s.windows(2).all(|w| w[0] < w[1]) && s[15] < 100);
        let offsets: std::collections::BTreeSet<usize> = s.iter().map(|x| x % 8).collect();
        assert_eq!(offsets.len(), 8, "{s:?}");
        assert_eq!(spread_samples(3, 16), vec![0, 1, 2]);
    }

    #[test]
    fn packets_in_decode_order_rank_their_timestamps() {
        // I P B B (decode order) with an edit-list offset: frames 0 3 1 2.
        let p = parse_packets("1024,900,K__\n4096,300,__\n2048,50,__\n3072,60,__\n").unwrap();
        let frames: Vec<usize> = p.iter().map(|p| p.frame).collect();
        assert_eq!(frames, vec![0, 3, 1, 2]);
        // Frame 1 (a B-frame) needs the I-frame, the P-frame and itself.
        assert_eq!(frames_to_show(&p, 1), Some((3, 1250)));
        assert_eq!(frames_to_show(&p, 0), Some((1, 900)));
        assert_eq!(frames_to_show(&p, 7), None);
    }

    #[test]
    fn a_later_gop_starts_at_its_own_key_frame() {
        let p = parse_packets("0,900,K_\n1,100,__\n2,800,K_\n3,70,__\n").unwrap();
        assert_eq!(frames_to_show(&p, 3), Some((2, 870)));
    }

    #[test]
    fn malformed_ffprobe_lines_are_errors_naming_the_line() {
        let e = parse_packets("0,900,K_\n12,abc\n").unwrap_err().to_string();
        assert!(e.contains("line 2"), "{e}");
    }
}

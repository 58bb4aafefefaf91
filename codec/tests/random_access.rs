//! Random access and decode timing as measured by the report: the pyramid
//! reads only the header and the sample's blocks, per texture.

use codec::report::{path_decode_times, pyramid_random_access, spread_samples};
use codec::synth::{SynthSpec, scene};
use codec::{Container, EncodeOptions, ParamGrid, Target, encode_to_file};

#[test]
fn a_cold_random_access_reads_the_header_and_one_block_per_texture() {
    let input = scene(&SynthSpec::cube(2, 2, ParamGrid::one_d(40), 16));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.ptxc");
    encode_to_file(
        &input,
        Target::Ratio(200.0),
        &EncodeOptions::default(),
        &path,
    )
    .unwrap();

    let c = Container::open(&path).unwrap();
    let header = c.bytes_read();
    let samples = spread_samples(40, 6);
    let access = pyramid_random_access(&path, &samples, 1).unwrap();
    assert_eq!(access.samples, samples.len());
    assert!(access.ms > 0.0);
    // Every access reads the header and exactly its blocks: one per texture.
    let expected: Vec<u64> = samples
        .iter()
        .map(|&s| {
            header
                + c.textures()
                    .iter()
                    .map(|t| {
                        let (b, _) = t.locate([s as u32, 0]).unwrap();
                        u64::from(c.block_entries()[b].len)
                    })
                    .sum::<u64>()
        })
        .collect();
    let mut sorted = expected.clone();
    sorted.sort_unstable();
    assert_eq!(access.bytes_read, sorted[sorted.len() / 2]);
    assert!(access.bytes_read < c.file_len() / 2, "{access:?}");
    // Dealt over threads: the same reads.
    let parallel = pyramid_random_access(&path, &samples, 3).unwrap();
    assert_eq!(parallel.bytes_read, access.bytes_read);
    assert_eq!(parallel.name, "pyramid, 3 threads");
}

#[test]
fn path_decode_times_one_per_leaf_and_stop_when_told() {
    let input = scene(&SynthSpec::cube(1, 2, ParamGrid::one_d(10), 16));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.ptxc");
    encode_to_file(
        &input,
        Target::Ratio(50.0),
        &EncodeOptions::default(),
        &path,
    )
    .unwrap();
    let c = Container::open(&path).unwrap();
    let times = path_decode_times(&c, &|| true).unwrap();
    assert_eq!(
        times.len(),
        2 * 10,
        "one timed decode per texture and sample"
    );
    assert!(times.iter().all(|t| t.is_finite() && *t >= 0.0));
    let asked = std::cell::Cell::new(0);
    let stopped = path_decode_times(&c, &|| {
        asked.set(asked.get() + 1);
        asked.get() <= 5
    })
    .unwrap();
    assert!(
        stopped.is_empty(),
        "the first five decodes are the untimed pass"
    );
}

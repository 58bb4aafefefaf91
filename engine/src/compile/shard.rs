//! A share of a scene's viewpoint samples for one process of a farmed
//! compile (`engine compile --shard I/N`): whole warm chains, dealt round
//! robin, so every shard infers exactly the bits one process would.

use super::infer::WARM_CHAIN;
use anyhow::{Result, bail};

/// Shard `index` of `count` (0-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    /// Parses `I/N` with 0 ≤ I < N.
    pub fn parse(s: &str) -> Result<Shard> {
        let parsed = s
            .split_once('/')
            .and_then(|(i, n)| Some((i.trim().parse().ok()?, n.trim().parse().ok()?)));
        match parsed {
            Some((index, count)) if index < count => Ok(Shard { index, count }),
            _ => bail!("--shard {s:?}: expected I/N with 0 ≤ I < N, e.g. 0/4"),
        }
    }

    /// This shard's samples out of `total`: chain c (samples
    /// c·WARM_CHAIN …) belongs to shard c mod N.
    pub fn samples(&self, total: u32) -> Vec<u32> {
        (0..total)
            .filter(|k| (k / WARM_CHAIN) % self.count == self.index)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_samples_in_whole_chains() {
        let total = 100;
        let mut seen = vec![0u32; total as usize];
        for index in 0..4 {
            let shard = Shard { index, count: 4 };
            let samples = shard.samples(total);
            for &k in &samples {
                seen[k as usize] += 1;
                // A sample inside a chain travels with its predecessor.
                if k % WARM_CHAIN != 0 {
                    assert!(samples.contains(&(k - 1)), "sample {k} without {}", k - 1);
                }
            }
        }
        assert!(seen.iter().all(|&n| n == 1), "{seen:?}");
    }

    #[test]
    fn bad_shards_are_refused_with_the_expected_form() {
        assert_eq!(Shard::parse("3/4").ok(), Some(Shard { index: 3, count: 4 }));
        for bad in ["4/4", "1", "a/b", "-1/4", "0/0", ""] {
            let e = Shard::parse(bad).err().map(|e| e.to_string());
            assert!(e.is_some_and(|e| e.contains("expected I/N")), "{bad}");
        }
    }
}

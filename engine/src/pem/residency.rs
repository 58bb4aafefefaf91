//! Which viewpoint samples are resident in a reflector's slots: the
//! samples a frame needs stay, a missing one replaces the least recently
//! used slot the frame does not need. Pure bookkeeping (the images live
//! with the reflector), so it is tested without a device.

/// Slots per reflector: the four corners a 2D blend needs, up to four
/// more being filled ahead for the next cell while a frame reads those,
/// and two so moving back and forth across a line does not re-decode.
pub const SLOTS: usize = 10;

/// What a slot holds.
#[derive(Clone, Copy, Debug, Default)]
struct Slot {
    sample: Option<u32>,
    /// The frame that last used it.
    used: u64,
    /// Being written ahead of need (by the decode worker): neither read by
    /// a frame nor given to another sample until [`SlotTable::filled`].
    filling: bool,
}

/// What each slot holds and when it was last used.
#[derive(Clone, Debug, Default)]
pub struct SlotTable {
    slots: Vec<Slot>,
}

impl SlotTable {
    pub fn new(slots: usize) -> Self {
        Self {
            slots: vec![Slot::default(); slots],
        }
    }

    /// The slot holding `sample` (resident or being filled).
    pub fn find(&self, sample: u32) -> Option<usize> {
        self.slots.iter().position(|s| s.sample == Some(sample))
    }

    pub fn holds(&self, sample: u32) -> bool {
        self.find(sample).is_some()
    }

    /// The (slot, sample) pairs being filled ahead.
    pub fn filling_slots(&self) -> Vec<(usize, u32)> {
        (self.slots.iter().enumerate())
            .filter_map(|(i, s)| s.sample.filter(|_| s.filling).map(|k| (i, k)))
            .collect()
    }

    /// Whether slot `slot` is being filled ahead.
    pub fn filling(&self, slot: usize) -> bool {
        self.slots.get(slot).is_some_and(|s| s.filling)
    }

    /// The least recently used slot that holds none of `keep` and is not
    /// being filled.
    fn victim(&self, keep: &[u32]) -> Option<usize> {
        (0..self.slots.len())
            .filter(|&i| {
                let s = &self.slots[i];
                !s.filling && s.sample.is_none_or(|k| !keep.contains(&k))
            })
            .min_by_key(|&i| self.slots[i].used)
    }

    /// Makes every sample of `needed` resident at `frame`: returns the
    /// (sample, slot) pairs that must be filled now; held ones are only
    /// marked used (those being filled ahead must be waited for). None
    /// when `needed` does not fit the slots left.
    pub fn assign(&mut self, needed: &[u32], frame: u64) -> Option<Vec<(u32, usize)>> {
        let mut fills = Vec::new();
        for &sample in needed {
            if let Some(i) = self.find(sample) {
                self.slots[i].used = frame;
                continue;
            }
            let victim = self.victim(needed)?;
            self.slots[victim] = Slot {
                sample: Some(sample),
                used: frame,
                filling: false,
            };
            fills.push((sample, victim));
        }
        Some(fills)
    }

    /// A slot for `sample` to be filled ahead of need, keeping `keep` (the
    /// samples a frame in flight reads) and every slot being filled: marks
    /// it filling. None when no slot is free for it.
    pub fn reserve(&mut self, sample: u32, keep: &[u32], frame: u64) -> Option<usize> {
        let victim = self.victim(keep)?;
        self.slots[victim] = Slot {
            sample: Some(sample),
            used: frame,
            filling: true,
        };
        Some(victim)
    }

    /// Slot `slot` was filled ahead: frames may read it.
    pub fn filled(&mut self, slot: usize) {
        if let Some(s) = self.slots.get_mut(slot) {
            s.filling = false;
        }
    }

    /// Filling slot `slot` failed: it holds nothing.
    pub fn abandon(&mut self, slot: usize) {
        if let Some(s) = self.slots.get_mut(slot) {
            *s = Slot::default();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn needed_samples_stay_and_the_least_recently_used_goes() {
        let mut t = SlotTable::new(3);
        assert_eq!(t.assign(&[4, 5], 1), Some(vec![(4, 0), (5, 1)]));
        assert_eq!(t.assign(&[5, 6], 2), Some(vec![(6, 2)]));
        // 4 was used longest ago and is not needed: its slot takes 7.
        assert_eq!(t.assign(&[6, 7], 3), Some(vec![(7, 0)]));
        assert!(t.holds(5) && t.holds(6) && t.holds(7) && !t.holds(4));
        // Back and forth across a sample decodes nothing.
        assert_eq!(t.assign(&[6, 5], 4), Some(vec![]));
        assert_eq!(t.assign(&[6, 7], 5), Some(vec![]));
    }

    #[test]
    fn a_slot_filled_ahead_is_neither_evicted_nor_given_away() {
        let mut t = SlotTable::new(3);
        assert_eq!(t.assign(&[1], 1), Some(vec![(1, 0)]));
        // Filled ahead while frame 1 (reading 1) is in flight.
        let s2 = t.reserve(2, &[1], 1).expect("a free slot");
        let s3 = t.reserve(3, &[1], 1).expect("a free slot");
        assert!(t.filling(s2) && t.filling(s3) && !t.filling(0));
        // No slot is left: 1 is read, 2 and 3 are being written.
        assert_eq!(t.reserve(4, &[1], 1), None);
        assert_eq!(t.assign(&[1, 4], 2), None);
        // A frame needing 2 finds it held (the caller waits for it).
        assert_eq!(t.assign(&[2], 2), Some(vec![]));
        t.filled(s2);
        // Once filled, 3 may go; while filling it could not.
        assert_eq!(t.assign(&[2, 5], 3), Some(vec![(5, 0)]));
        t.abandon(s3);
        assert!(!t.holds(3) && !t.filling(s3));
        assert_eq!(t.assign(&[2, 5, 6], 4), Some(vec![(6, s3)]));
    }

    #[test]
    fn more_samples_than_slots_is_refused() {
        let mut t = SlotTable::new(2);
        assert_eq!(t.assign(&[1, 2, 3], 1), None);
        let mut t = SlotTable::new(4);
        let fills = t.assign(&[1, 2, 3, 4], 1).expect("fits");
        assert_eq!(fills.len(), 4);
        assert_eq!(t.assign(&[1, 2, 3, 4], 2), Some(vec![]));
    }
}

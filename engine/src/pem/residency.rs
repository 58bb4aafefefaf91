//! Which viewpoint samples are resident in a reflector's slots: the
//! samples a frame needs stay, a missing one replaces the least recently
//! used slot the frame does not need. Pure bookkeeping (the images live
//! with the reflector), so it is tested without a device.

/// Samples kept resident per reflector: the four corners a 2D blend needs
/// plus two, so moving back and forth across a line does not re-decode.
pub const SLOTS: usize = 6;

/// What each slot holds and when it was last used.
#[derive(Clone, Debug, Default)]
pub struct SlotTable {
    slots: Vec<(Option<u32>, u64)>,
}

impl SlotTable {
    pub fn new(slots: usize) -> Self {
        Self {
            slots: vec![(None, 0); slots],
        }
    }

    /// The slot holding `sample`, if it is resident.
    pub fn find(&self, sample: u32) -> Option<usize> {
        self.slots.iter().position(|s| s.0 == Some(sample))
    }

    pub fn holds(&self, sample: u32) -> bool {
        self.find(sample).is_some()
    }

    /// Makes every sample of `needed` resident at `frame`: returns the
    /// (sample, slot) pairs that must be filled now; resident ones are only
    /// marked used. None when `needed` has more samples than slots.
    pub fn assign(&mut self, needed: &[u32], frame: u64) -> Option<Vec<(u32, usize)>> {
        let mut fills = Vec::new();
        for &sample in needed {
            if let Some(i) = self.find(sample) {
                self.slots[i].1 = frame;
                continue;
            }
            let victim = (0..self.slots.len())
                .filter(|&i| self.slots[i].0.is_none_or(|s| !needed.contains(&s)))
                .min_by_key(|&i| self.slots[i].1)?;
            self.slots[victim] = (Some(sample), frame);
            fills.push((sample, victim));
        }
        Some(fills)
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
    fn more_samples_than_slots_is_refused() {
        let mut t = SlotTable::new(2);
        assert_eq!(t.assign(&[1, 2, 3], 1), None);
        let mut t = SlotTable::new(4);
        let fills = t.assign(&[1, 2, 3, 4], 1).expect("fits");
        assert_eq!(fills.len(), 4);
        assert_eq!(t.assign(&[1, 2, 3, 4], 2), Some(vec![]));
    }
}

//! A node's free symbols as a bit set over the arena's symbol slots.
//!
//! Every node interned records the symbols it holds (`Meta::free`). As
//! sorted lists, the union for a new sum or product walked every child's
//! list and sorted the result; a 100-link pendulum's terms hold a few
//! hundred symbols each, and that union was about 8 % of `lagc check`.
//! As bits it is one OR per 64 slots and child, and the first 64 slots
//! (every symbol of most models) are stored inline, without an allocation.

/// A set of symbol slots: slot `i` is bit `i % 64` of word `i / 64`; the
/// first word inline, the others boxed (trailing zero words trimmed, so
/// equal sets are equal values).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct FreeSet {
    first: u64,
    rest: Box<[u64]>,
}

impl FreeSet {
    pub(crate) fn single(slot: u32) -> FreeSet {
        let mut words = vec![0u64; slot as usize / 64 + 1];
        words[slot as usize / 64] = 1 << (slot % 64);
        FreeSet::from_words(&words)
    }

    /// The set of the bits of `words` (word 0 first).
    pub(crate) fn from_words(words: &[u64]) -> FreeSet {
        let used = words.iter().rposition(|&w| w != 0).map_or(0, |i| i + 1);
        FreeSet {
            first: words.first().copied().unwrap_or(0),
            rest: if used > 1 {
                words[1..used].into()
            } else {
                Box::new([])
            },
        }
    }

    fn word(&self, i: usize) -> u64 {
        match i {
            0 => self.first,
            _ => self.rest.get(i - 1).copied().unwrap_or(0),
        }
    }

    fn words(&self) -> usize {
        1 + self.rest.len()
    }

    pub(crate) fn contains(&self, slot: u32) -> bool {
        self.word(slot as usize / 64) >> (slot % 64) & 1 == 1
    }

    /// Whether the two sets share a slot.
    pub(crate) fn meets(&self, other: &FreeSet) -> bool {
        (0..self.words().min(other.words())).any(|i| self.word(i) & other.word(i) != 0)
    }

    /// ORs the set into `words` (grown as needed).
    pub(crate) fn or_into(&self, words: &mut Vec<u64>) {
        if words.len() < self.words() {
            words.resize(self.words(), 0);
        }
        words[0] |= self.first;
        for (w, &r) in words[1..].iter_mut().zip(self.rest.iter()) {
            *w |= r;
        }
    }

    /// The slots, ascending.
    pub(crate) fn iter(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.words()).flat_map(move |i| {
            let mut w = self.word(i);
            std::iter::from_fn(move || {
                (w != 0).then(|| {
                    let bit = w.trailing_zeros();
                    w &= w - 1;
                    i as u32 * 64 + bit
                })
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::FreeSet;

    #[test]
    fn bits_round_trip_through_words_and_iteration() {
        let slots = [0u32, 3, 63, 64, 130, 200];
        let mut words = Vec::new();
        for &s in &slots {
            FreeSet::single(s).or_into(&mut words);
        }
        let set = FreeSet::from_words(&words);
        assert_eq!(set.iter().collect::<Vec<_>>(), slots);
        assert!(slots.iter().all(|&s| set.contains(s)));
        assert!(!set.contains(1) && !set.contains(65) && !set.contains(1000));
        assert!(set.meets(&FreeSet::single(130)));
        assert!(!set.meets(&FreeSet::single(131)));
        // Trailing zero words are trimmed: equal sets are equal values.
        assert_eq!(FreeSet::from_words(&[5, 0, 0]), FreeSet::from_words(&[5]));
        assert_eq!(FreeSet::default().iter().count(), 0);
    }
}

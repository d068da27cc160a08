//! Response-time summaries shared by the protocols (`--stats`): bounded memory whatever the
//! number of responses.
//!
//! [`Times`] keeps the count, minimum and maximum exactly, and the samples themselves for the
//! first [`EXACT_SAMPLES`] responses (the median is exact). Beyond that the samples move into a
//! histogram with three significant digits (exact below 1 ms, one bucket above 1000 s), so one
//! summary never holds more than about 26 kB.

/// Response times are kept exactly below this many µs …
const EXACT: u64 = 1_000;
/// … and with three significant digits up to this many µs (1000 s); above in one bucket.
const TOP: u64 = 1_000_000_000;
/// Buckets per decade above `EXACT`.
const PER_DECADE: usize = 900;
const DECADES: usize = 6; // 1e3 .. 1e9
const BUCKETS: usize = EXACT as usize + DECADES * PER_DECADE + 1;

#[inline]
fn bucket(v: u64) -> usize {
    // One decade after the other, each with its width as a constant: a division by a constant
    // is a multiplication. A loop over the decades divided by a variable width, a 64-bit
    // `div` for every response above 1 ms (SAB2 to TSV: 3 % of the time).
    const fn at(decade: usize, low: u64, v: u64) -> usize {
        EXACT as usize + decade * PER_DECADE + ((v - low) / (low / 100)) as usize
    }
    const _: () = assert!(TOP == EXACT * 1_000_000 && DECADES == 6);
    match v {
        0..1_000 => v as usize,
        1_000..10_000 => at(0, 1_000, v),
        10_000..100_000 => at(1, 10_000, v),
        100_000..1_000_000 => at(2, 100_000, v),
        1_000_000..10_000_000 => at(3, 1_000_000, v),
        10_000_000..100_000_000 => at(4, 10_000_000, v),
        100_000_000..1_000_000_000 => at(5, 100_000_000, v),
        _ => BUCKETS - 1,
    }
}

/// Smallest value of a bucket.
fn bucket_low(i: usize) -> u64 {
    if i < EXACT as usize {
        return i as u64;
    }
    let d = (i - EXACT as usize) / PER_DECADE;
    if d >= DECADES {
        return TOP;
    }
    let r = ((i - EXACT as usize) % PER_DECADE) as u64;
    let low = EXACT * 10u64.pow(d as u32);
    low + r * (low / 100)
}

/// Samples kept exactly per summary; beyond this many the median comes from the histogram.
pub const EXACT_SAMPLES: usize = 4_096;

/// Most bytes one summary holds on the heap (the histogram, or the exact samples).
#[cfg(test)]
pub const MAX_HEAP_BYTES: usize = if BUCKETS > EXACT_SAMPLES {
    BUCKETS * 4
} else {
    EXACT_SAMPLES * 4
};

/// Response times (µs) of one device: exact count, minimum and maximum; the median exactly for
/// the first `EXACT_SAMPLES` samples, then from a histogram.
#[derive(Clone, Debug, Default)]
pub struct Times {
    pub count: u64,
    pub min: u64,
    pub max: u64,
    samples: Vec<u32>,
    hist: Option<Box<[u32]>>,
}

impl Times {
    pub fn add(&mut self, micros: u64) {
        if self.count == 0 {
            self.min = micros;
            self.max = micros;
        } else {
            self.min = self.min.min(micros);
            self.max = self.max.max(micros);
        }
        self.count += 1;
        // The histogram once it exists (the common case in a long run), without a call.
        if let Some(hist) = self.hist.as_deref_mut() {
            if let Some(slot) = hist.get_mut(bucket(micros)) {
                *slot = slot.saturating_add(1);
            }
            return;
        }
        if self.samples.len() < EXACT_SAMPLES {
            self.samples.push(micros.min(u32::MAX as u64) as u32);
            return;
        }
        let slot = &mut self.histogram()[bucket(micros)];
        *slot = slot.saturating_add(1);
    }

    /// The histogram, created from the exact samples on first use (they are dropped).
    fn histogram(&mut self) -> &mut [u32] {
        if self.hist.is_none() {
            let mut hist = vec![0u32; BUCKETS].into_boxed_slice();
            for v in std::mem::take(&mut self.samples) {
                let slot = &mut hist[bucket(v as u64)];
                *slot = slot.saturating_add(1);
            }
            self.hist = Some(hist);
        }
        self.hist.as_deref_mut().expect("just created")
    }

    /// Adds every sample of `other` (exact while both stay under the cap together).
    pub fn merge(&mut self, other: &Times) {
        if other.count == 0 {
            return;
        }
        let (min, max) = if self.count == 0 {
            (other.min, other.max)
        } else {
            (self.min.min(other.min), self.max.max(other.max))
        };
        let count = self.count + other.count;
        if self.hist.is_none()
            && other.hist.is_none()
            && self.samples.len() + other.samples.len() <= EXACT_SAMPLES
        {
            self.samples.extend_from_slice(&other.samples);
        } else {
            let hist = self.histogram();
            match &other.hist {
                Some(h) => {
                    for (a, b) in hist.iter_mut().zip(h.iter()) {
                        *a = a.saturating_add(*b);
                    }
                }
                None => {
                    for &v in &other.samples {
                        let slot = &mut hist[bucket(v as u64)];
                        *slot = slot.saturating_add(1);
                    }
                }
            }
        }
        (self.count, self.min, self.max) = (count, min, max);
    }

    /// The sample of 0-based `rank` in sorted order, and whether it is exact (otherwise it has
    /// three significant digits).
    pub fn nth(&self, rank: u64) -> Option<(u64, bool)> {
        if let Some(hist) = &self.hist {
            let mut seen = 0u64;
            for (i, &c) in hist.iter().enumerate() {
                seen += c as u64;
                if seen > rank && c > 0 {
                    return Some((bucket_low(i).clamp(self.min, self.max), false));
                }
            }
            return (self.count > 0).then_some((self.max, false));
        }
        if rank as usize >= self.samples.len() {
            return None;
        }
        let mut v = self.samples.clone();
        let (_, m, _) = v.select_nth_unstable(rank as usize);
        Some((*m as u64, true))
    }

    /// The median (the lower one for an even count).
    pub fn median(&self) -> Option<(u64, bool)> {
        self.nth(self.count.checked_sub(1)? / 2)
    }

    /// The median (the upper one for an even count).
    pub fn median_upper(&self) -> Option<(u64, bool)> {
        self.nth(self.count / 2)
    }

    /// Bytes held on the heap (for tests of the bound).
    #[doc(hidden)]
    pub fn heap_bytes(&self) -> usize {
        self.samples.capacity() * 4 + self.hist.as_ref().map_or(0, |h| h.len() * 4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The buckets as defined: decade after decade from `EXACT`, each `PER_DECADE` buckets of
    /// a hundredth of the decade's low end.
    fn bucket_by_decades(v: u64) -> usize {
        if v < EXACT {
            return v as usize;
        }
        let (mut low, mut index) = (EXACT, EXACT as usize);
        while low < TOP {
            if v < low * 10 {
                return index + ((v - low) / (low / 100)) as usize;
            }
            index += PER_DECADE;
            low *= 10;
        }
        BUCKETS - 1
    }

    #[test]
    fn buckets_are_the_decades_buckets() {
        let mut edges = vec![u64::MAX, u64::MAX - 1];
        let mut p = 1u64;
        for _ in 0..=10 {
            edges.extend([p.saturating_sub(1), p, p + 1, p * 5 + 7]);
            p *= 10;
        }
        // Every value up to 2 ms, then a spread up to 1000 s and beyond.
        let spread = (0..2_000_000u64).chain((0..200_000u64).map(|i| i * i * 31 + i));
        for v in edges.into_iter().chain(spread) {
            assert_eq!(bucket(v), bucket_by_decades(v), "{v}");
        }
    }

    #[test]
    fn buckets_are_monotonic_and_tight() {
        let mut last = 0;
        for v in [
            0,
            1,
            999,
            1000,
            1009,
            1010,
            9999,
            10_000,
            123_456,
            999_999_999,
            1 << 40,
        ] {
            let b = bucket(v);
            assert!(b >= last, "{v}");
            last = b;
            let low = bucket_low(b);
            assert!(low <= v, "{v}: {low}");
            if v < TOP {
                // three significant digits
                assert!(v - low <= v / 100, "{v}: {low}");
            }
        }
        assert_eq!(bucket(u64::MAX), BUCKETS - 1);
        for i in 0..BUCKETS {
            assert_eq!(bucket(bucket_low(i)), i, "{i}");
        }
    }

    #[test]
    fn median_min_max() {
        let mut t = Times::default();
        assert_eq!(t.median(), None);
        assert_eq!(t.median_upper(), None);
        for v in [500, 100, 300, 2_345, 12_345] {
            t.add(v);
        }
        assert_eq!((t.min, t.max, t.count), (100, 12_345, 5));
        assert_eq!(t.median(), Some((500, true)));
        t.add(1_234);
        // Lower and upper median of 100 300 500 1234 2345 12345.
        assert_eq!(t.median(), Some((500, true)));
        assert_eq!(t.median_upper(), Some((1_234, true)));
        t.add(1_215);
        t.add(1_215);
        assert_eq!(t.median(), Some((1_215, true)));
    }

    #[test]
    fn median_beyond_the_exact_samples() {
        let mut t = Times::default();
        let mut all = Vec::new();
        for i in 0..EXACT_SAMPLES as u64 * 3 + 1001 {
            let v = 1_000 + (i * 7_919) % 2_000;
            t.add(v);
            all.push(v);
        }
        all.sort_unstable();
        let want = all[(all.len() - 1) / 2];
        let (m, exact) = t.median().unwrap();
        assert!(!exact);
        // three significant digits, never above the true value
        assert!(m <= want && want - m <= want / 100, "{m} {want}");
        assert_eq!((t.min, t.max), (1_000, 2_999));
    }

    #[test]
    fn memory_stays_bounded_and_exact_under_the_cap() {
        let mut t = Times::default();
        let mut x = 12_345u64;
        let mut all = Vec::new();
        for i in 0..EXACT_SAMPLES as u64 * 50 {
            // spread over every decade
            x = x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            let v = (x >> 33) % 10u64.pow(1 + (i % 9) as u32);
            t.add(v);
            if all.len() < EXACT_SAMPLES {
                all.push(v);
                all.sort_unstable();
                let want = all[(all.len() - 1) / 2];
                assert_eq!(t.median(), Some((want, true)), "{} samples", all.len());
            }
            assert!(t.heap_bytes() <= MAX_HEAP_BYTES, "{i}: {}", t.heap_bytes());
        }
        assert_eq!(t.count, EXACT_SAMPLES as u64 * 50);
        const { assert!(MAX_HEAP_BYTES < 32 * 1024) };
    }

    #[test]
    fn merge_adds_counts_and_samples() {
        let mut a = Times::default();
        let mut b = Times::default();
        for v in [5, 7, 9] {
            a.add(v);
        }
        for v in [1, 100] {
            b.add(v);
        }
        a.merge(&b);
        assert_eq!((a.count, a.min, a.max), (5, 1, 100));
        assert_eq!(a.median(), Some((7, true)));
        let mut big = Times::default();
        for v in 0..EXACT_SAMPLES as u64 {
            big.add(v % 500);
        }
        a.merge(&big);
        assert_eq!(a.count, EXACT_SAMPLES as u64 + 5);
        assert!(!a.median().unwrap().1, "beyond the cap: from the histogram");
        assert!(a.heap_bytes() <= MAX_HEAP_BYTES);
        let mut c = Times::default();
        c.merge(&a);
        assert_eq!((c.count, c.min, c.max), (a.count, 0, 499));
    }
}

//! Samples to scanline bins as they stream in: the mean of each run of `k` samples.
//!
//! A Ping360 sends up to 1200 samples per ping; the sonar module's scanlines carry at most
//! [`crate::sonar::MAX_BINS`], and the board's RAM is the tightest budget. So the driver never
//! holds a ping's samples: each arrives, is added to its group's sum, and each full group of
//! `k = ⌈n / POOL_BINS⌉` becomes one bin, its mean (rounded). A trailing partial group (at
//! most `k − 1` samples, the farthest) is left out, so every bin covers exactly `k` samples
//! and the scanline's range is `bins × k` samples.
//!
//! Why [`POOL_BINS`] = 300: at the default 30 m it is 0.1 m per bin (the Micron-like default
//! of the HIL sonar, and a fifth of the evidence map's 0.5 m cell); for 1200 samples it is a
//! mean of 4. A mean, not a maximum, so the background's speckle is not raised by the pooling
//! (the maximum of four exponential samples has twice their mean); a real echo spans many
//! samples (a 16 µs pulse is 7 samples at the recording's 1.7 mm spacing) and survives it.

/// Most bins per ping (bytes of RAM for one ping).
pub const POOL_BINS: usize = 300;

/// The bins of the ping being received.
#[derive(Clone, Debug)]
pub struct Pool {
    bins: [u8; POOL_BINS],
    /// Samples per bin.
    k: u16,
    /// Bins this ping gives.
    len: u16,
    /// Bins completed.
    filled: u16,
    /// Sum and count of the group being added up.
    sum: u32,
    in_group: u16,
}

impl Default for Pool {
    fn default() -> Self {
        Self::new()
    }
}

impl Pool {
    /// An empty pool.
    pub const fn new() -> Self {
        Pool {
            bins: [0; POOL_BINS],
            k: 1,
            len: 0,
            filled: 0,
            sum: 0,
            in_group: 0,
        }
    }

    /// Starts a ping of `samples` samples.
    pub fn start(&mut self, samples: u16) {
        let cap = POOL_BINS as u16;
        self.k = samples.div_ceil(cap).max(1);
        self.len = samples / self.k;
        self.filled = 0;
        self.sum = 0;
        self.in_group = 0;
    }

    /// Adds the next samples (beyond the announced count, they are ignored).
    pub fn push(&mut self, samples: &[u8]) {
        for &s in samples {
            if self.filled >= self.len {
                return;
            }
            self.sum += u32::from(s);
            self.in_group += 1;
            if self.in_group == self.k {
                // `k` is at least 1 (`start`); said again so the division has no panic path.
                let k = u32::from(self.k.max(1));
                // A mean of u8s is a u8.
                let mean = ((self.sum + k / 2) / k).min(255) as u8;
                if let Some(b) = self.bins.get_mut(usize::from(self.filled)) {
                    *b = mean;
                }
                self.filled += 1;
                self.sum = 0;
                self.in_group = 0;
            }
        }
    }

    /// Samples per bin of the current ping.
    pub fn factor(&self) -> u16 {
        self.k
    }

    /// The bins, once every one is complete.
    pub fn bins(&self) -> Option<&[u8]> {
        (self.len > 0 && self.filled == self.len)
            .then(|| self.bins.get(..usize::from(self.len)))
            .flatten()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_pings_pass_through_and_large_ones_are_averaged() {
        let mut p = Pool::new();
        p.start(3);
        p.push(&[1, 2]);
        assert_eq!(p.bins(), None);
        p.push(&[3, 99]);
        assert_eq!(p.bins(), Some(&[1u8, 2, 3][..]));
        assert_eq!(p.factor(), 1);

        // 1200 samples → groups of 4 → 300 bins, in any chunking.
        let samples: [u8; 1200] = core::array::from_fn(|i| (i % 8) as u8 * 30);
        p.start(1200);
        for c in samples.chunks(7) {
            p.push(c);
        }
        assert_eq!(p.factor(), 4);
        let bins = p.bins().unwrap();
        assert_eq!(bins.len(), 300);
        // Groups alternate 0,30,60,90 (mean 45) and 120,150,180,210 (mean 165).
        assert_eq!(&bins[..4], &[45, 165, 45, 165]);

        // 601 samples: groups of 3 → 200 bins, the last sample left out.
        p.start(601);
        p.push(&[255; 601]);
        assert_eq!(p.bins().map(<[u8]>::len), Some(200));
        // No samples: no bins.
        p.start(0);
        assert_eq!(p.bins(), None);
    }
}

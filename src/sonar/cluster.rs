//! Clustering of echo runs across adjacent beams of one sweep, in a fixed-capacity table.
//!
//! Beams are numbered by the extractor (a missing ping advances the number by more than one).
//! The hits of beam k are paired with open clusters whose last hit is on an earlier beam and
//! whose last range is within `cluster_gap_m` of the hit's range, closest pair first; each
//! cluster takes at most one hit per beam (so a beam's near and far runs never fold into one
//! cluster). A hit that joins nothing opens a new cluster; when all [`MAX_CLUSTERS`] slots are taken it is dropped
//! ([`Assign::Full`]) and the open clusters carry on — see the module docs of `sonar` for why
//! the table cannot fill with a validated configuration.

use heapless::Vec;

use super::fit::{Hit, Moments};
use super::{MAX_CLUSTERS, MAX_RUNS_PER_BEAM};

/// Ranges closer than this are one echo's (a range recomputed from its world point), m.
const SAME_RANGE_M: f32 = 0.01;

/// One open cluster.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Cluster {
    /// Its running sums.
    pub moments: Moments,
    /// Leading-edge range of its last hit, m.
    pub last_range: f32,
    /// Beam number of its first hit.
    pub first_beam: u32,
    /// Beam number of its last hit.
    pub last_beam: u32,
    /// Head travel since its first hit, rad.
    pub span_rad: f32,
    /// Ping time of its last hit, ms.
    pub time_ms: u64,
    /// A neighbouring beam returned an echo (strong or weak) beside one of its hits.
    pub seconded: bool,
}

impl Cluster {
    /// Beams from the first to the last hit, inclusive.
    pub fn spanned(&self) -> u32 {
        self.last_beam
            .wrapping_sub(self.first_beam)
            .saturating_add(1)
    }

    /// Beams since the last hit, as seen at beam `beam` (0 when hit on `beam`).
    pub fn since(&self, beam: u32) -> u32 {
        beam.wrapping_sub(self.last_beam)
    }
}

/// What became of a hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Assign {
    /// It continued the cluster in this slot.
    Joined(usize),
    /// It opened a cluster in this slot.
    Opened(usize),
    /// No cluster continued and the table was full: the hit was dropped.
    Full,
}

/// The open clusters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Table {
    slots: [Option<Cluster>; MAX_CLUSTERS],
}

impl Table {
    /// An empty table.
    pub const fn new() -> Self {
        Table {
            slots: [None; MAX_CLUSTERS],
        }
    }

    /// Open clusters.
    pub fn len(&self) -> usize {
        self.slots.iter().filter(|s| s.is_some()).count()
    }

    /// Drops every cluster.
    pub fn clear(&mut self) {
        self.slots = [None; MAX_CLUSTERS];
    }

    /// Adds `ad` radians of head travel to every open cluster.
    pub fn advance(&mut self, ad: f32) {
        for c in self.slots.iter_mut().flatten() {
            c.span_rad += ad;
        }
    }

    /// Assigns one beam's hits (at beam `beam`, time `time_ms`), returning what became of each,
    /// in order. Pairs are taken globally nearest in range first, so a speckle run just in front
    /// of a surface cannot take the surface's cluster from the surface's own run; hits left
    /// over open clusters. At most [`MAX_RUNS_PER_BEAM`] hits are taken (the rest are ignored).
    pub fn assign_beam(
        &mut self,
        hits: &[Hit],
        beam: u32,
        time_ms: u64,
        gap_m: f32,
    ) -> Vec<Assign, MAX_RUNS_PER_BEAM> {
        let mut fate: [Option<Assign>; MAX_RUNS_PER_BEAM] = [None; MAX_RUNS_PER_BEAM];
        // Each round joins one pair; at most one round per hit.
        for _ in 0..MAX_RUNS_PER_BEAM {
            let mut best: Option<(usize, usize, f32)> = None;
            for (h, hit) in hits.iter().enumerate() {
                if !matches!(fate.get(h), Some(None)) {
                    continue;
                }
                for (i, slot) in self.slots.iter().enumerate() {
                    let Some(c) = slot else { continue };
                    let d = (hit.range - c.last_range).abs();
                    if c.last_beam != beam && d <= gap_m && best.is_none_or(|b| d < b.2) {
                        best = Some((h, i, d));
                    }
                }
            }
            let Some((h, i, _)) = best else { break };
            if let (Some(hit), Some(Some(c)), Some(f)) =
                (hits.get(h), self.slots.get_mut(i), fate.get_mut(h))
            {
                c.moments.add(hit);
                c.last_range = hit.range;
                c.last_beam = beam;
                c.time_ms = c.time_ms.max(time_ms);
                *f = Some(Assign::Joined(i));
            }
        }
        let mut out = Vec::new();
        for (hit, f) in hits.iter().zip(fate) {
            let a = f.unwrap_or_else(|| self.open(hit, beam, time_ms));
            // `hits` is cut to the capacity by the zip with `fate`.
            let _ = out.push(a);
        }
        out
    }

    /// Opens a cluster with `hit`, or reports the table full.
    fn open(&mut self, hit: &Hit, beam: u32, time_ms: u64) -> Assign {
        match self.slots.iter_mut().enumerate().find(|(_, s)| s.is_none()) {
            Some((i, slot)) => {
                *slot = Some(Cluster {
                    moments: Moments::new(hit),
                    last_range: hit.range,
                    first_beam: beam,
                    last_beam: beam,
                    span_rad: 0.0,
                    time_ms,
                    seconded: false,
                });
                Assign::Opened(i)
            }
            None => Assign::Full,
        }
    }

    /// Marks seconded the cluster whose last hit is on beam `beam` at range `range_m`, if any.
    pub fn second(&mut self, beam: u32, range_m: f32) {
        for c in self.slots.iter_mut().flatten() {
            if c.last_beam == beam && (c.last_range - range_m).abs() <= SAME_RANGE_M {
                c.seconded = true;
            }
        }
    }

    /// Removes every cluster for which `close` holds and hands it to `each`.
    pub fn close_where(&mut self, close: impl Fn(&Cluster) -> bool, mut each: impl FnMut(Cluster)) {
        for slot in self.slots.iter_mut() {
            if slot.as_ref().is_some_and(&close) {
                if let Some(c) = slot.take() {
                    each(c);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;

    fn hit(x: f32, range: f32) -> Hit {
        Hit {
            point: Vec2::new(x, range),
            look: Vec2::new(0.0, 1.0),
            range,
            step: 0.03,
            intensity: 150.0,
        }
    }

    fn one(t: &mut Table, h: Hit, beam: u32, time_ms: u64) -> Assign {
        t.assign_beam(&[h], beam, time_ms, 1.0)[0]
    }

    #[test]
    fn hits_join_the_nearest_range_within_the_gap() {
        let mut t = Table::new();
        let first = t.assign_beam(&[hit(0.0, 10.0), hit(0.0, 14.0)], 1, 0, 1.0);
        assert_eq!(first.as_slice(), &[Assign::Opened(0), Assign::Opened(1)]);
        // Same beam: cannot join either cluster, even at the same range.
        assert_eq!(one(&mut t, hit(0.1, 10.0), 1, 0), Assign::Opened(2));
        assert_eq!(t.len(), 3);
        // Next beam: 13.4 is 0.6 from the 14 m cluster and 3.4 from the 10 m ones.
        assert_eq!(one(&mut t, hit(0.3, 13.4), 2, 7), Assign::Joined(1));
        t.close_where(
            |c| c.since(2) == 0,
            |c| {
                assert_eq!((c.moments.hits(), c.spanned(), c.time_ms), (2, 2, 7));
                assert_eq!(c.last_range, 13.4);
            },
        );
        assert_eq!(t.len(), 2);
        assert_eq!(one(&mut t, hit(0.3, 13.4), 2, 7), Assign::Opened(1));
        assert_eq!(one(&mut t, hit(0.3, 16.0), 2, 7), Assign::Opened(3));
        let mut closed = 0;
        t.close_where(
            |c| c.since(2) > 0,
            |c| {
                assert!(c.last_range == 10.0);
                closed += 1;
            },
        );
        assert_eq!(closed, 2);
        assert_eq!(t.len(), 2);
    }

    #[test]
    fn a_nearer_speckle_run_does_not_steal_the_surface_cluster() {
        let mut t = Table::new();
        one(&mut t, hit(0.0, 9.86), 1, 0);
        // Speckle at 8.89 (0.97 m off, within the gap) comes first along the beam; the surface
        // run at 9.79 is nearer in range to the cluster and must get it.
        let got = t.assign_beam(&[hit(0.1, 8.89), hit(0.1, 9.79)], 2, 0, 1.0);
        assert_eq!(got.as_slice(), &[Assign::Opened(1), Assign::Joined(0)]);
        // Two runs, two clusters: each continues its own.
        let got = t.assign_beam(&[hit(0.2, 8.95), hit(0.2, 9.75)], 3, 0, 1.0);
        assert_eq!(got.as_slice(), &[Assign::Joined(1), Assign::Joined(0)]);
    }

    #[test]
    fn full_table_drops_the_new_cluster_and_keeps_the_old() {
        let mut t = Table::new();
        for k in 0..MAX_CLUSTERS {
            let r = 2.0 + 3.0 * k as f32;
            assert_eq!(one(&mut t, hit(0.0, r), 1, 0), Assign::Opened(k));
        }
        // A continuing hit still finds its cluster; a new one is dropped.
        let got = t.assign_beam(&[hit(0.0, 100.0), hit(0.1, 5.2)], 2, 0, 1.0);
        assert_eq!(got.as_slice(), &[Assign::Full, Assign::Joined(1)]);
        assert_eq!(t.len(), MAX_CLUSTERS);
        t.advance(0.5);
        t.close_where(|c| c.span_rad >= 0.5, |_| {});
        assert_eq!(t.len(), 0);
        one(&mut t, hit(0.0, 1.0), 3, 0);
        t.clear();
        assert_eq!(t.len(), 0);
    }
}

//! How far a fleet is from seed 001's formation lattice (q, λ, θ₀), and whether it is one group.

use vpf::planner::Formation;
use vpf::Vec2;

/// Distance from `d` to the nearest point u·a1 + v·a2 (u, v integers) of a Bravais lattice.
fn to_bravais(d: Vec2, a1: Vec2, a2: Vec2) -> f32 {
    let det = a1.cross(a2);
    let u = d.cross(a2) / det;
    let v = a1.cross(d) / det;
    let mut best = f32::INFINITY;
    for cu in [u.floor(), u.ceil()] {
        for cv in [v.floor(), v.ceil()] {
            best = best.min((d - a1 * cu - a2 * cv).norm());
        }
    }
    best
}

/// Distance from the offset `d` (from a vehicle taken as a node) to the nearest node of the
/// lattice through that vehicle. For the honeycomb the vehicle may be on either sublattice:
/// `flip` says it is on the θ₀ + π one.
fn to_lattice(f: &Formation, d: Vec2, flip: bool) -> f32 {
    let l = f.lattice_m;
    let e = |a: f32| Vec2::from_angle(f.orientation + a) * l;
    let third = std::f32::consts::TAU / 3.0;
    match f.q {
        4 => to_bravais(d, e(0.0), e(std::f32::consts::FRAC_PI_2)),
        6 => to_bravais(d, e(0.0), e(std::f32::consts::FRAC_PI_3)),
        _ => {
            // Honeycomb: a triangular Bravais lattice of side √3·λ with a two-node basis, the
            // vehicle and its neighbour along θ₀ (or θ₀ + π on the other sublattice).
            let s = if flip { -1.0 } else { 1.0 };
            let (a1, a2) = ((e(0.0) - e(third)) * s, (e(0.0) - e(2.0 * third)) * s);
            to_bravais(d, a1, a2).min(to_bravais(d - e(0.0) * s, a1, a2))
        }
    }
}

/// The lattice-shape error of a fleet, relative to λ: the lattice (of the formation's q, λ and
/// orientation) is laid through one vehicle, every vehicle's distance to its nearest node is
/// taken, and the worst of them is the error of that placement; the result is the best
/// placement over the vehicles (and, for the honeycomb, over both sublattices). Zero for a
/// fleet exactly on lattice nodes — diagonal neighbours (√2·λ for q = 4) included.
pub fn lattice_error(f: &Formation, ps: &[Vec2]) -> f32 {
    let mut best = f32::INFINITY;
    for &anchor in ps {
        for flip in [false, true] {
            let worst = ps
                .iter()
                .map(|&p| to_lattice(f, p - anchor, flip))
                .fold(0.0f32, f32::max);
            best = best.min(worst);
        }
    }
    best / f.lattice_m
}

/// Number of groups: vehicles within the formation's neighbour shell of each other (between the
/// lattice's first and second rings) are linked, and a group is a connected set.
pub fn groups(f: &Formation, ps: &[Vec2]) -> usize {
    let shell = f.neighbour_shell();
    let mut group: Vec<usize> = (0..ps.len()).collect();
    fn root(g: &mut [usize], mut i: usize) -> usize {
        while g[i] != i {
            g[i] = g[g[i]];
            i = g[i];
        }
        i
    }
    for i in 0..ps.len() {
        for j in i + 1..ps.len() {
            if (ps[i] - ps[j]).norm() <= shell {
                let (a, b) = (root(&mut group, i), root(&mut group, j));
                group[a] = b;
            }
        }
    }
    (0..ps.len()).filter(|&i| root(&mut group, i) == i).count()
}

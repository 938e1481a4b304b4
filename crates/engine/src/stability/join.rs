//! Which fast multipliers the coupled exponents nearest zero supersede.
//!
//! A point of a model with a thermal field has two estimates of its exponents near zero:
//! the monodromy product of the frozen-temperature problem (every mechanical exponent,
//! without the thermal coupling) and Hill's eigenproblem of the coupled balance in a disk
//! around zero (exact, thermal and mechanical together, [`super::hill_near_zero`]). The
//! verdict counts the disk's exponents and the product's multipliers that are not
//! estimates of one of them: the disk holds `exponents.len() − thermal` mechanical
//! exponents, so that many of the product's multipliers are superseded.
//!
//! By default those with `|ln μ|/P` below the disk's radius. Where the coupling reorders
//! the modes by modulus the radius cannot tell them apart: a frozen real pair `μ₁, μ₂ > 1`
//! that the coupling turns into the disk's complex pair (the thermo-mechanical
//! Neimark–Sacker mechanism, `docs/stability.md`) may have a third, stable multiplier
//! between them in modulus, and a mode whose two estimates lie on both sides of the edge
//! is lost or counted twice. Two rules decide instead:
//!
//! Both rest on the disk holding every thermal exponent; where the radius's count is off
//! by more than one mode it does not (a thermal node of small capacity decays faster
//! than the disk reaches), and the radius decides.
//!
//! - **The sum.** The coupling moves each exponent but keeps their sum nearly (a trace):
//!   of the multipliers with `|ln μ|/P` below the disk's reach (the next exponent of the
//!   balance beyond it, at most twice its radius), the superseded ones are
//!   those whose `Σ Re ln μ / P` is nearest the sum of the disk's mechanical exponents
//!   (the disk's exponents but its `thermal` nearest zero). It overrides the radius only
//!   when it matches the sum less than half as well and worse by more than the target's
//!   own uncertainty (four times the largest modulus of the `thermal` exponents: a slow
//!   mechanical exponent taken for a thermal one moves the target by up to twice that).
//! - **The fold parity.** A branch of the balance that has passed an odd number of folds
//!   has an odd number of real exponents above zero (`det J` changes sign at each fold).
//!   When the choice above gives the other parity and another choice that matches the
//!   sum within the same uncertainty gives the branch's, that one is taken: the counts
//!   agree with the branch without a parity correction.

use num_complex::Complex64;

use super::{BifurcationKind, NearZero, NearZeroDisk, UNIT_CIRCLE_TOL};

/// More candidates than this and the radius decides (2^12 subsets at most).
const MAX_CANDIDATES: usize = 12;

/// The exponents `ln μ / P` of the fast multipliers `fast` (`None` for `μ = 0`).
fn rates(fast: &[Complex64], period: f64) -> Vec<Option<Complex64>> {
    fast.iter()
        .map(|m| (m.norm() > 0.0).then(|| m.ln() / period))
        .collect()
}

/// How many of a disk's `n` exponents are mechanical, with `thermal` of them the thermal
/// equations'; `None` when unknown (`thermal` 0) or impossible.
fn mechanical(n: usize, thermal: usize) -> Option<usize> {
    n.checked_sub(thermal).filter(|_| thermal > 0)
}

/// Whether a radius's count of product exponents inside and the disk's mechanical count
/// are off by more than one mode: then the thermal equations' exponents are not all in
/// the disk (a thermal node of small capacity decays fast), the mechanical count is
/// unknown, and the radius decides.
fn counts_disagree(inside: usize, mech: usize) -> bool {
    inside.abs_diff(mech) > 1
}

/// The disk's edge placed where its set `nz` and a frozen-temperature monodromy product
/// with multipliers `fast` (orbit period `period`, s) agree on how many mechanical
/// exponents lie inside: `exponents.len() − thermal` of the product's exponents
/// `|ln μ|/P` below the edge, the next one above it.
///
/// The same mode has two estimates, the set's coupled exponent and the product's frozen
/// one, which differ by the thermal coupling. An edge that falls between the two loses
/// the mode (the product's estimate is superseded, the coupled one is not in the set) or
/// counts it twice; it happens wherever the edge, halfway to the next converged
/// exponent, meets the product's estimate. The set's radius is kept when it agrees
/// already, or when no edge between the largest kept modulus and [`NearZero::outer`] (at
/// most twice the radius) does, or when the counts disagree by more than one mode.
pub(super) fn edge(nz: &NearZero, fast: &[Complex64], period: f64) -> f64 {
    let Some(mech) = mechanical(nz.exponents.len(), nz.thermal) else {
        return nz.radius;
    };
    let mut p: Vec<f64> = rates(fast, period)
        .into_iter()
        .flatten()
        .map(|r| r.norm())
        .collect();
    p.sort_by(f64::total_cmp);
    if counts_disagree(p.iter().filter(|x| **x < nz.radius).count(), mech) {
        return nz.radius;
    }
    let inner = nz.exponents.iter().map(|l| l.norm()).fold(0.0, f64::max);
    let lo = inner.max(match mech {
        0 => 0.0,
        m => p.get(m - 1).copied().unwrap_or(f64::INFINITY),
    });
    let hi = nz
        .outer
        .min(2.0 * nz.radius)
        .min(p.get(mech).copied().unwrap_or(f64::INFINITY));
    if lo >= hi || (lo < nz.radius && nz.radius < hi) {
        nz.radius
    } else {
        0.5 * (lo + hi)
    }
}

/// The superseded flags (one per entry of `fast`) for the disk `disk` holding the
/// exponents `near` (sorted by modulus); with `odd_folds`, the fold parity of the branch.
pub(super) fn superseded(
    fast: &[Complex64],
    near: &[Complex64],
    disk: &NearZeroDisk,
    odd_folds: Option<bool>,
) -> Vec<bool> {
    let rate = rates(fast, disk.period);
    let by_radius: Vec<bool> = rate
        .iter()
        .map(|r| r.is_some_and(|r| r.norm() < disk.radius))
        .collect();
    let Some(mech) = mechanical(near.len(), disk.thermal) else {
        return by_radius;
    };
    let inside = by_radius.iter().filter(|f| **f).count();
    if counts_disagree(inside, mech) {
        return by_radius;
    }
    let target: f64 = near.iter().skip(disk.thermal).map(|l| l.re).sum();
    let slack = 4.0
        * near
            .iter()
            .take(disk.thermal)
            .map(|l| l.norm())
            .fold(0.0, f64::max);
    // the product's estimates of the disk's modes lie within twice its radius
    let reach = disk.outer.max(disk.radius).min(2.0 * disk.radius);
    let candidates: Vec<usize> = (0..fast.len())
        .filter(|&i| rate[i].is_some_and(|r| r.norm() < reach))
        .collect();
    if candidates.len() > MAX_CANDIDATES || candidates.len() < mech {
        return by_radius;
    }
    let re = |i: usize| rate[i].map_or(0.0, |r| r.re);
    let chosen_by = |mask: u32| {
        candidates
            .iter()
            .enumerate()
            .filter(move |(k, _)| mask >> k & 1 == 1)
            .map(|(_, &i)| i)
    };
    let mismatch = |sum: f64| (sum - target).abs();
    // the real exponents above zero of the joint set, for the parity: the disk's real
    // ones and the product's real ones above +1 it does not supersede
    let near_real = near
        .iter()
        .filter(|l| BifurcationKind::of_exponent(**l) == BifurcationKind::SaddleNode)
        .filter(|l| l.re > disk.tol())
        .count();
    let real_above = |i: usize| {
        BifurcationKind::of_multiplier(fast[i]) == BifurcationKind::SaddleNode
            && fast[i].norm() > 1.0 + UNIT_CIRCLE_TOL
    };
    let all_real_above = (0..fast.len()).filter(|&i| real_above(i)).count();
    let parity_of = |superseded_real_above: usize| {
        (near_real + all_real_above - superseded_real_above) % 2 == 1
    };
    // each subset of `mech` candidates: its mismatch, its mask
    let subsets: Vec<(f64, u32)> = (0u32..(1 << candidates.len()))
        .filter(|mask| mask.count_ones() as usize == mech)
        .map(|mask| (mismatch(chosen_by(mask).map(re).sum()), mask))
        .collect();
    let Some(&(best, best_mask)) = subsets.iter().min_by(|a, b| a.0.total_cmp(&b.0)) else {
        return by_radius;
    };
    let flags_of = |mask: u32| {
        let mut f = vec![false; fast.len()];
        chosen_by(mask).for_each(|i| f[i] = true);
        f
    };
    let base = if inside == mech {
        mismatch((0..fast.len()).filter(|&i| by_radius[i]).map(re).sum())
    } else {
        f64::INFINITY
    };
    let (chosen_d, chosen) = if best < 0.5 * base && base - best > slack {
        (best, flags_of(best_mask))
    } else {
        (base.min(best + slack), by_radius)
    };
    let Some(odd) = odd_folds else {
        return chosen;
    };
    let chosen_real = (0..fast.len())
        .filter(|&i| chosen[i] && real_above(i))
        .count();
    if parity_of(chosen_real) == odd {
        return chosen;
    }
    subsets
        .iter()
        .filter(|(d, mask)| {
            *d <= chosen_d + slack
                && parity_of(chosen_by(*mask).filter(|&i| real_above(i)).count()) == odd
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map_or(chosen, |&(_, mask)| flags_of(mask))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(re: f64, im: f64) -> Complex64 {
        Complex64::new(re, im)
    }

    /// 27 thermal exponents near zero and the disk's mechanical ones, sorted by modulus.
    fn disk_set(mech: &[Complex64]) -> Vec<Complex64> {
        let mut v: Vec<Complex64> = (1..=27).map(|k| c(-0.03 * k as f64, 0.0)).collect();
        v.extend_from_slice(mech);
        v
    }

    fn disk(omega: f64, radius: f64) -> NearZeroDisk {
        NearZeroDisk {
            radius,
            period: std::f64::consts::TAU / omega,
            outer: 26.0,
            thermal: 27,
        }
    }

    /// The two-disk rotor at 603.92 rad/s (`examples/rotors/two_disk_ball_bearings.toml`,
    /// order 3): the frozen real pair 1.0399, 1.2340 became the disk's pair 13.14 ± 9.15i;
    /// the stable 0.8201 lies between them in modulus, so the radius alone supersedes the
    /// stable one and counts the unstable 1.2340 besides the pair.
    #[test]
    fn a_pair_the_coupling_formed_supersedes_its_frozen_origins_not_a_bystander() {
        let fast = [
            c(1.0399, 0.0),
            c(0.8201, 0.0),
            c(1.2340, 0.0),
            c(0.7024, 0.0),
        ];
        let near = disk_set(&[c(13.144, -9.151), c(13.144, 9.151)]);
        let d = disk(603.9207, 19.635);
        assert_eq!(
            fast.iter().map(|m| d.holds(*m)).collect::<Vec<_>>(),
            [true, true, false, false]
        );
        assert_eq!(
            superseded(&fast, &near, &d, None),
            [true, false, true, false]
        );
    }

    /// 670.41 rad/s: the radius supersedes 1.0062 and 0.8585 (sum −15.6 1/s); the pair
    /// 0.8263 ± 0.4091i sums to −17.3 1/s, the disk's mechanical pair to −16.8.
    fn close_call() -> ([Complex64; 4], Vec<Complex64>, NearZeroDisk) {
        let fast = [
            c(1.0062, 0.0),
            c(0.8585, 0.0),
            c(0.8263, 0.4091),
            c(0.8263, -0.4091),
        ];
        let near = disk_set(&[c(-0.984, 0.0), c(-15.787, 0.0)]);
        let mut d = disk(670.4061, 32.835);
        d.outer = 60.0;
        (fast, near, d)
    }

    /// A choice that the sum cannot tell from the radius's (within the thermal
    /// exponents' uncertainty) keeps the radius's.
    #[test]
    fn a_close_call_keeps_the_radius() {
        let (fast, near, d) = close_call();
        assert_eq!(
            superseded(&fast, &near, &d, None),
            [true, true, false, false]
        );
    }

    /// A frozen real pair turned complex: at 604.83 rad/s the frozen 0.9689 and 0.8802
    /// have met in the stable pair 0.9228 ± 0.0386i, while the disk still holds the
    /// coupled pair 11.32 ± 8.47i they and 1.2474 formed. The radius supersedes the stable
    /// pair and counts 1.2474 beside the disk's pair; the sum supersedes 1.2474 and one
    /// of the stable pair (the other stays counted, inside the circle).
    #[test]
    fn a_frozen_pair_turned_complex_does_not_leave_its_partner_counted() {
        let fast = [
            c(0.9228, 0.0386),
            c(0.9228, -0.0386),
            c(1.2474, 0.0),
            c(0.6930, 0.0),
        ];
        let near = disk_set(&[c(11.316, -8.468), c(11.316, 8.468)]);
        let d = disk(604.8337, 19.565);
        let flags = superseded(&fast, &near, &d, None);
        assert!(flags[2] && !flags[3], "{flags:?}");
        assert_eq!(flags.iter().filter(|f| **f).count(), 2);
    }

    /// The fold parity decides among choices the sum cannot tell apart: the close call
    /// above on a branch that has passed an odd number of folds supersedes the complex
    /// pair and counts 1.0062 as the real multiplier above +1 the parity asks for.
    #[test]
    fn the_fold_parity_decides_what_the_sum_cannot() {
        let (fast, near, d) = close_call();
        assert_eq!(
            superseded(&fast, &near, &d, Some(false)),
            [true, true, false, false]
        );
        assert_eq!(
            superseded(&fast, &near, &d, Some(true)),
            [false, false, true, true]
        );
    }
}

//! The interval means of one product, stored on the entries that are nonzero somewhere.
//!
//! The pointwise derivative arrays of [`NonlinearEval`] are dense (on the dual rotor about
//! 1 700 numbers, 36 × 46 of them in `D`), but each bearing's force depends on its own
//! rings and a few temperatures and each heat source on its bearing's load: about 200
//! entries are ever nonzero. A product keeps one mean per interval (512 + 256 on the
//! default settings); held densely they were 10 MB per evaluation, allocated and zeroed
//! afresh, and every pass over them (the orbit mean, the coarse pairs, the fluctuations,
//! the factors' nonzero scan) ran over all the zeros.
//!
//! [`SparseMeans`] keeps the union of the nonzero entries over all intervals (the
//! *slots*, in the order of [`StateSpace::for_each_derivative_slot`]) and, per interval,
//! one value per slot. Every operation does, entry by entry, the arithmetic of the dense
//! arrays in the same order (an entry outside the slots is zero in every mean, and stays
//! zero in their sums, pair averages and fluctuations), so the products are the same to
//! the last bit (test `sparse_means_equal_the_dense_means`).

use rayon::prelude::*;

use crate::integrate::{StateSpace, Workspace};
use crate::stability::sip::{MeanGrid, interval_means_with};
use crate::system::{NonlinearEval, PeriodicOrbit};

/// Block numbers of the velocity derivatives `df_dv`, `dg_dv`
/// ([`NonlinearEval::derivative_blocks`]).
const VELOCITY_BLOCKS: [usize; 2] = [1, 4];

/// Interval means (or their fluctuations about the orbit mean) on their nonzero entries.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SparseMeans {
    /// `(block, index)` of each kept entry, in the derivative matrix's row order.
    slots: Vec<(usize, usize)>,
    /// One row of `slots.len()` values per interval.
    values: Vec<f64>,
    intervals: usize,
}

impl SparseMeans {
    /// Samples the interval means on `grid`, as
    /// [`crate::stability::sip::interval_means`] does.
    pub(crate) fn sample(
        space: &StateSpace<'_>,
        orbit: &dyn PeriodicOrbit,
        grid: MeanGrid<'_>,
        ws: &mut Workspace,
    ) -> Self {
        let offsets = block_offsets(&ws.eval);
        // each interval's nonzeros as (flat position, value), in block order
        let lists = interval_means_with(space, orbit, grid, ws, |m| nonzero_list(m, &offsets));
        Self::from_lists(space, &offsets, &lists)
    }

    /// The means from each interval's nonzeros `(flat position, value)`.
    fn from_lists(
        space: &StateSpace<'_>,
        offsets: &[usize; 7],
        lists: &[Vec<(usize, f64)>],
    ) -> Self {
        let mut used = vec![false; offsets[6]];
        for &(at, _) in lists.iter().flatten() {
            used[at] = true;
        }
        let (slots, position) = slots_of(space, offsets, &used);
        let width = slots.len();
        let mut values = vec![0.0; lists.len() * width];
        values
            .par_chunks_mut(width.max(1))
            .zip(lists)
            .with_min_len(64)
            .for_each(|(row, list)| {
                for &(at, v) in list {
                    row[position[at]] = v;
                }
            });
        Self {
            slots,
            values,
            intervals: lists.len(),
        }
    }

    /// The same means from dense ones.
    #[cfg(test)]
    pub(crate) fn from_dense(space: &StateSpace<'_>, means: &[NonlinearEval]) -> Self {
        let Some(first) = means.first() else {
            return Self {
                slots: Vec::new(),
                values: Vec::new(),
                intervals: 0,
            };
        };
        let offsets = block_offsets(first);
        let lists: Vec<_> = means.iter().map(|m| nonzero_list(m, &offsets)).collect();
        Self::from_lists(space, &offsets, &lists)
    }

    /// Number of intervals.
    pub(crate) fn len(&self) -> usize {
        self.intervals
    }

    /// Interval `k`'s values, one per slot (in the order of [`Self::layout`]).
    pub(crate) fn row(&self, k: usize) -> &[f64] {
        let width = self.slots.len();
        &self.values[k * width..(k + 1) * width]
    }

    /// `e`'s value at every slot.
    pub(crate) fn at_slots(&self, e: &NonlinearEval) -> Vec<f64> {
        let blocks = e.derivative_blocks();
        self.slots.iter().map(|&(b, k)| blocks[b][k]).collect()
    }

    pub(crate) fn rows(&self) -> impl Iterator<Item = &[f64]> {
        (0..self.intervals).map(|k| self.row(k))
    }

    /// `out` (cleared first) `= Σ_k w · mean_k`, summed in interval order.
    pub(crate) fn weighted_sum(&self, w: f64, out: &mut NonlinearEval) {
        out.clear();
        let blocks = out.derivative_blocks_mut();
        for row in self.rows() {
            for (&(b, k), &v) in self.slots.iter().zip(row) {
                blocks[b][k] += w * v;
            }
        }
    }

    /// Whether some mean has a nonzero velocity derivative.
    pub(crate) fn reads_velocity(&self) -> bool {
        self.slots.iter().any(|(b, _)| VELOCITY_BLOCKS.contains(b))
    }

    /// The means of the intervals two at a time: `(0 + m_{2k}/2) + m_{2k+1}/2` (the
    /// order of the dense arrays' `clear` and two `axpy`s). `intervals` must be even.
    pub(crate) fn pair_averages(&self) -> Self {
        let width = self.slots.len();
        let mut values = vec![0.0; self.intervals / 2 * width];
        values
            .par_chunks_mut(width.max(1))
            .enumerate()
            .with_min_len(32)
            .for_each(|(k, out)| {
                let a = &self.values[2 * k * width..(2 * k + 1) * width];
                let b = &self.values[(2 * k + 1) * width..(2 * k + 2) * width];
                for ((o, &a), &b) in out.iter_mut().zip(a).zip(b) {
                    *o += 0.5 * a;
                    *o += 0.5 * b;
                }
            });
        Self {
            slots: self.slots.clone(),
            values,
            intervals: self.intervals / 2,
        }
    }

    /// Every mean `m_k ← m_k − mean` (the fluctuations about `mean`). `mean` must
    /// be zero outside the slots, as an orbit mean of these means (or part of it) is.
    pub(crate) fn subtract(&mut self, mean: &NonlinearEval) {
        let of_mean = self.at_slots(mean);
        let width = self.slots.len();
        self.values
            .par_chunks_mut(width.max(1))
            .with_min_len(64)
            .for_each(|row| {
                for (v, &m) in row.iter_mut().zip(&of_mean) {
                    *v -= m;
                }
            });
    }

    /// Where each slot sits in `space`'s derivative matrix (`None`: a velocity entry that
    /// `space` does not gather).
    pub(crate) fn layout(&self, space: &StateSpace<'_>) -> Vec<Option<(usize, usize)>> {
        let mut at = std::collections::HashMap::with_capacity(self.slots.len());
        space.for_each_derivative_slot(|b, k, i, j| {
            at.insert((b, k), (i, j));
        });
        self.slots.iter().map(|s| at.get(s).copied()).collect()
    }

    /// The nonzero entries `(row, column, value)` of interval `k`'s derivative matrix, in
    /// the order of [`StateSpace::derivative_nonzeros`], into `out` (cleared first);
    /// `layout` from [`Self::layout`].
    pub(crate) fn nonzeros(
        &self,
        k: usize,
        layout: &[Option<(usize, usize)>],
        out: &mut Vec<(usize, usize, f64)>,
    ) {
        out.clear();
        let width = self.slots.len();
        let row = &self.values[k * width..(k + 1) * width];
        for (&v, place) in row.iter().zip(layout) {
            if let Some((i, j)) = *place
                && v != 0.0
            {
                out.push((i, j, v));
            }
        }
    }
}

/// Start of each derivative block in one flat numbering, and the total (index 6).
fn block_offsets(eval: &NonlinearEval) -> [usize; 7] {
    let mut offsets = [0; 7];
    for (b, block) in eval.derivative_blocks().iter().enumerate() {
        offsets[b + 1] = offsets[b] + block.len();
    }
    offsets
}

/// The nonzero entries of `m`'s derivative arrays as (flat position, value).
fn nonzero_list(m: &NonlinearEval, offsets: &[usize; 7]) -> Vec<(usize, f64)> {
    m.derivative_blocks()
        .iter()
        .enumerate()
        .flat_map(|(b, block)| {
            block
                .iter()
                .enumerate()
                .filter(|(_, v)| **v != 0.0)
                .map(move |(k, &v)| (offsets[b] + k, v))
        })
        .collect()
}

/// The used entries as slots in the derivative matrix's order, and each flat position's
/// slot (`usize::MAX` when unused).
///
/// Entries the derivative matrix leaves out (velocity derivatives without the velocity
/// gather) are appended after the others, so that none is lost.
fn slots_of(
    space: &StateSpace<'_>,
    offsets: &[usize; 7],
    used: &[bool],
) -> (Vec<(usize, usize)>, Vec<usize>) {
    let mut slots = Vec::new();
    let mut position = vec![usize::MAX; used.len()];
    let mut take = |b: usize, k: usize| {
        let at = offsets[b] + k;
        if used[at] && position[at] == usize::MAX {
            position[at] = slots.len();
            slots.push((b, k));
        }
    };
    space.for_each_derivative_slot(|b, k, _, _| take(b, k));
    for b in VELOCITY_BLOCKS {
        for k in 0..offsets[b + 1] - offsets[b] {
            take(b, k);
        }
    }
    (slots, position)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::SampledOrbit;
    use crate::stability::sip::{axpy_derivs, gauss_legendre, interval_means};
    use crate::systems::chain::Chain;

    /// The sparse means against the dense arrays they replace, operation by operation, to
    /// the last bit: the sampled means, the orbit mean, the coarse pair averages and the
    /// fluctuations' nonzero lists (values and order), on a chain with three contacts and
    /// two hot nodes whose derivative arrays are mostly structural zeros.
    #[test]
    fn sparse_means_equal_the_dense_means() {
        let sys = Chain::with_contacts(6, 4, 3, 2);
        let omega = 1.3;
        let space = StateSpace::new(&sys, omega).expect("state space");
        let period = 2.0 * std::f64::consts::PI / omega;
        let dim = 2 * 6 + 4;
        let samples: Vec<Vec<f64>> = (0..32)
            .map(|s| {
                let t = s as f64 / 32.0 * 2.0 * std::f64::consts::PI;
                (0..dim)
                    .map(|i| 0.3 * (t + i as f64).sin() + 0.1 * (2.0 * t).cos() + 0.01 * i as f64)
                    .collect()
            })
            .collect();
        let orbit = SampledOrbit::new(omega, period, 0.0, 6, 4, &samples);
        let (nodes, weights) = gauss_legendre(2).expect("gauss points");
        let n_k = 64;
        let delta = period / n_k as f64;
        let mut ws = space.workspace();
        let grid = MeanGrid {
            delta,
            intervals: n_k,
            nodes,
            weights,
        };
        let dense = interval_means(&space, &orbit, grid, &mut ws);
        let sparse = SparseMeans::sample(&space, &orbit, grid, &mut ws);
        assert_eq!(sparse.len(), n_k);
        assert!(sparse.reads_velocity());
        let full: usize = dense[0].derivative_blocks().iter().map(|b| b.len()).sum();
        assert!(
            sparse.slots.len() < full / 2,
            "{} of {full} entries kept: the test needs structural zeros",
            sparse.slots.len()
        );
        assert_eq!(sparse, SparseMeans::from_dense(&space, &dense));

        // the orbit mean
        let w = 1.0 / n_k as f64;
        let mut want = ws.eval.clone();
        want.clear();
        for m in &dense {
            axpy_derivs(&mut want, w, m);
        }
        let mut got = ws.eval.clone();
        sparse.weighted_sum(w, &mut got);
        assert_eq!(got.derivative_blocks(), want.derivative_blocks());

        // the coarse pairs
        let pairs: Vec<NonlinearEval> = dense
            .chunks_exact(2)
            .map(|pair| {
                let mut m = pair[0].clone();
                m.clear();
                axpy_derivs(&mut m, 0.5, &pair[0]);
                axpy_derivs(&mut m, 0.5, &pair[1]);
                m
            })
            .collect();
        assert_eq!(
            sparse.pair_averages(),
            SparseMeans {
                slots: sparse.slots.clone(),
                ..SparseMeans::from_dense(&space, &pairs)
            }
        );

        // the fluctuations' nonzeros, with one block of the mean zeroed as the field split
        // does, with and without the velocity gather
        want.dg_dx.iter_mut().for_each(|v| *v = 0.0);
        let mut fluct = sparse.clone();
        fluct.subtract(&want);
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for gather in [true, false] {
            let view = space.with_velocity_gather(gather);
            let layout = fluct.layout(&view);
            for (k, m) in dense.iter().enumerate() {
                let mut fl = m.clone();
                axpy_derivs(&mut fl, -1.0, &want);
                view.derivative_nonzeros(&fl, &mut a);
                fluct.nonzeros(k, &layout, &mut b);
                assert_eq!(a, b, "interval {k}, velocity gather {gather}");
            }
        }
    }
}

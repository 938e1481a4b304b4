//! The kicks in the coordinates the fluctuation uses.
//!
//! The fluctuation `D_k − D̄` of one product (one `(p+q) × g` matrix per interval) reads
//! and writes fewer directions than it has rows and columns. Some are exact: the
//! inter-shaft bearing's force depends on the difference of its rings' displacements and
//! acts on both rings with opposite signs, so on the dual rotor the ten mechanical rows and
//! columns carry eight directions, and a bearing's force depends on its temperatures
//! through one combination (the expansion `δv`). Others are negligible. The fluctuation's
//! singular values over all the intervals of a product (each block of rows against each
//! block of columns scaled to its largest) fall on the dual rotor, at every ω measured
//! between 300 and 690 rad/s, in the thermal rows and columns from 1 to about 2e-3 in
//! twelve directions, then jump to 3e-5 … 2e-7 in four more, and 1.4e-8 … 1e-10 (the
//! conductances of nearly unloaded contacts, held finite by the contact model) or exact
//! zeros in the rest.
//!
//! [`KickBasis`] finds these directions per field from the Gram matrices of the
//! fluctuation summed over the intervals (each block normalized to its largest eigenvalue,
//! so that forces and heat flows, displacements and temperatures count alike) and keeps
//! those whose singular value is above [`super::ExpSip::kick_rank_tol`]. The products then
//! gather and spread those directions only: with the default 1e-4, 8 + 12 on the dual
//! rotor instead of 10 + 26, a kick `G_k` 20 × 20 instead of 36 × 36 and the thermal
//! field's `[K₀ K₁]` 12 × 24 instead of 26 × 52. Measured on the default sweep against
//! the products on all rows and columns: the 27 bifurcations and 352 stable flags the
//! same, the multipliers above 1/2 within 5e-8; on 480–540 rad/s within 3e-9 with the
//! tolerance at 1e-7 or 1e-4 alike, and within 2e-4 at 1e-2 (which drops the directions
//! of 2e-3 … 1e-2).
//!
//! A Gram matrix squares the singular values: below about 1e-7 (the square root of the
//! rounding of its sums) a tolerance keeps directions that are rounding noise, harmless
//! for the products, only less compact.

use faer::{Mat, MatMut, Side};

use super::means::SparseMeans;
use crate::system::NonlinearEval;

/// A field's gathered rows and spread columns, `((g0, g1), (s0, s1))`.
pub(super) type FieldRanges = ((usize, usize), (usize, usize));

/// Orthonormal bases of the directions a product's fluctuation reads (per field's gathered
/// rows) and writes (per field's spread columns); see the module docs.
pub(super) struct KickBasis {
    fields: Vec<FieldBasis>,
    /// Where each slot of the means sits: its row, and its field of columns with the
    /// column within it (`None`: a slot outside the derivative matrix or the fields).
    slots: Vec<Option<Place>>,
    /// Original spread dimension (`p + q`).
    spread_dim: usize,
    /// Compressed gather and spread dimensions.
    dims: (usize, usize),
}

/// A slot's row in the derivative matrix, and its column as field and place in it.
#[derive(Clone, Copy)]
struct Place {
    row: usize,
    field: usize,
    col: usize,
}

/// One field's bases and where its directions sit, before and after.
struct FieldBasis {
    /// Number of original gathered rows, and the original spread columns.
    gather_len: usize,
    spread: (usize, usize),
    /// `V` (gathered rows × kept inputs) by rows and `U` (spread columns × kept outputs)
    /// by rows.
    v: Vec<f64>,
    u: Vec<f64>,
    /// Kept inputs and outputs.
    n_in: usize,
    n_out: usize,
    /// Start of the field's kept inputs and outputs in the compressed coordinates.
    gather_at: usize,
    spread_at: usize,
}

impl KickBasis {
    /// The bases of the fluctuations of `means` about `mean`, whose slots sit in the
    /// derivative matrix (`r` rows) as `layout` says, for fields with the original gather
    /// and spread ranges `ranges`. `None` when no field has a direction to drop (the
    /// products then run as they are), `tol` is not positive, or an eigenvalue problem
    /// fails.
    pub(super) fn new(
        means: &SparseMeans,
        mean: &NonlinearEval,
        layout: &[Option<(usize, usize)>],
        ranges: &[FieldRanges],
        r: usize,
        tol: f64,
    ) -> Option<Self> {
        if tol.is_nan() || tol <= 0.0 || ranges.is_empty() {
            return None;
        }
        let find = |i: usize, pick: fn(&FieldRanges) -> (usize, usize)| {
            ranges.iter().position(|f| {
                let (a, b) = pick(f);
                (a..b).contains(&i)
            })
        };
        // each slot's (row field, row in it, column field, column in it)
        let places: Vec<Option<[usize; 4]>> = layout
            .iter()
            .map(|at| {
                let (i, j) = (*at)?;
                let (fo, fi) = (find(i, |f| f.1)?, find(j, |f| f.0)?);
                Some([fo, i - ranges[fo].1.0, fi, j - ranges[fi].0.0])
            })
            .collect();
        let nf = ranges.len();
        let len = |(a, b): (usize, usize)| b - a;
        // Gram blocks: outputs of field a against the columns of field b (the slots that
        // share a column, in pairs), inputs of field a against the rows of field b
        // Gram blocks, their lower triangles, in one buffer: outputs of field a against the
        // columns of field b (from the slots that share a column, in pairs), then inputs of
        // field a against the rows of field b
        let mut blocks = Vec::with_capacity(2 * nf * nf);
        let mut at = 0;
        for n_of in [|f: &FieldRanges| f.1, |f: &FieldRanges| f.0] {
            for ab in 0..nf * nf {
                let n = len(n_of(&ranges[ab / nf]));
                blocks.push((at, n));
                at += n * n;
            }
        }
        let mut acc = vec![0.0; at];
        // (place in acc, first slot, second slot), each unordered pair once
        let mut pairs: Vec<(usize, usize, usize)> = Vec::new();
        let lower =
            |(start, n): (usize, usize), a: usize, b: usize| start + a.max(b) * n + a.min(b);
        for (s1, p1) in places.iter().enumerate() {
            let Some([fo1, i1, fi1, j1]) = *p1 else {
                continue;
            };
            for (s2, p2) in places.iter().enumerate().skip(s1) {
                let Some([fo2, i2, fi2, j2]) = *p2 else {
                    continue;
                };
                if layout[s1].map(|a| a.1) == layout[s2].map(|a| a.1) && fo1 == fo2 {
                    pairs.push((lower(blocks[fo1 * nf + fi1], i1, i2), s1, s2));
                }
                if layout[s1].map(|a| a.0) == layout[s2].map(|a| a.0) && fi1 == fi2 {
                    pairs.push((lower(blocks[nf * nf + fi1 * nf + fo1], j1, j2), s1, s2));
                }
            }
        }
        let of_mean = means.at_slots(mean);
        let mut x = vec![0.0; of_mean.len()];
        for row in means.rows() {
            for ((x, v), m) in x.iter_mut().zip(row).zip(&of_mean) {
                *x = v - m;
            }
            for &(at, s1, s2) in &pairs {
                acc[at] += x[s1] * x[s2];
            }
        }
        // the blocks as matrices (lower triangles; the eigenvalue problems read those)
        let gram = |(start, n): (usize, usize)| {
            Mat::from_fn(
                n,
                n,
                |i, j| if i >= j { acc[start + i * n + j] } else { 0.0 },
            )
        };
        let out: Vec<Mat<f64>> = blocks[..nf * nf].iter().map(|&b| gram(b)).collect();
        let inp: Vec<Mat<f64>> = blocks[nf * nf..].iter().map(|&b| gram(b)).collect();
        let mut fields = Vec::with_capacity(nf);
        let mut any_dropped = false;
        let (mut gather_at, mut spread_at) = (0, 0);
        for (a, &(gather, spread)) in ranges.iter().enumerate() {
            let (lo, li) = (len(spread), len(gather));
            let (eo, ro) = directions(&out[a * nf..(a + 1) * nf], lo, tol)?;
            let (ei, ri) = directions(&inp[a * nf..(a + 1) * nf], li, tol)?;
            // a square field (the thermal one, whose block updates need it) stays square
            let (ro, ri) = if lo == li {
                (ro.max(ri), ro.max(ri))
            } else {
                (ro, ri)
            };
            any_dropped |= ro < lo || ri < li;
            let by_rows = |e: &Mat<f64>, n: usize, kept: usize| {
                (0..n)
                    .flat_map(|i| (n - kept..n).map(move |c| (i, c)))
                    .map(|(i, c)| e[(i, c)])
                    .collect::<Vec<f64>>()
            };
            fields.push(FieldBasis {
                gather_len: li,
                spread,
                v: by_rows(&ei, li, ri),
                u: by_rows(&eo, lo, ro),
                n_in: ri,
                n_out: ro,
                gather_at,
                spread_at,
            });
            gather_at += ri;
            spread_at += ro;
        }
        let slots = places
            .iter()
            .zip(layout)
            .map(|(p, at)| {
                let [_, _, field, col] = (*p)?;
                Some(Place {
                    row: (*at)?.0,
                    field,
                    col,
                })
            })
            .collect();
        any_dropped.then_some(Self {
            fields,
            slots,
            spread_dim: r,
            dims: (gather_at, spread_at),
        })
    }

    /// Field `f`'s compressed gathered rows and spread columns.
    pub(super) fn ranges(&self, f: usize) -> ((usize, usize), (usize, usize)) {
        let b = &self.fields[f];
        (
            (b.gather_at, b.gather_at + b.n_in),
            (b.spread_at, b.spread_at + b.n_out),
        )
    }

    /// Field `f`'s bases `V` and `U` as matrices.
    fn bases(&self, f: usize) -> (Mat<f64>, Mat<f64>) {
        let b = &self.fields[f];
        let by_rows =
            |m: &[f64], rows: usize, cols: usize| Mat::from_fn(rows, cols, |i, c| m[i * cols + c]);
        (
            by_rows(&b.v, b.gather_len, b.n_in),
            by_rows(&b.u, b.spread.1 - b.spread.0, b.n_out),
        )
    }

    /// Field `f`'s gather `Vᵀ Ŝ` and spread `L̂ U` from its modal ones.
    pub(super) fn compress_field(
        &self,
        f: usize,
        s_hat: &Mat<f64>,
        l_hat: &Mat<f64>,
    ) -> (Mat<f64>, Mat<f64>) {
        let (v, u) = self.bases(f);
        (v.transpose() * s_hat, l_hat * &u)
    }

    /// Scratch for [`Self::compress`]: `D V` by rows, and one row of the result.
    pub(super) fn scratch(&self) -> Vec<f64> {
        vec![0.0; (self.spread_dim + 1) * self.dims.0]
    }

    /// `Uᵀ D V` into `out` (compressed spread × gather) from one interval's slot values
    /// `row`; `scratch` from [`Self::scratch`].
    pub(super) fn compress(&self, row: &[f64], scratch: &mut [f64], mut out: MatMut<'_, f64>) {
        let width = self.dims.0;
        let (t, acc) = scratch.split_at_mut(self.spread_dim * width);
        t.fill(0.0);
        // t = D V, by rows
        for (&x, place) in row.iter().zip(&self.slots) {
            let Some(p) = place else { continue };
            if x == 0.0 {
                continue;
            }
            let b = &self.fields[p.field];
            let v = &b.v[p.col * b.n_in..(p.col + 1) * b.n_in];
            let at = p.row * width + b.gather_at;
            for (t, v) in t[at..at + b.n_in].iter_mut().zip(v) {
                *t += x * v;
            }
        }
        // out = Uᵀ t, field by field (every row of `out` is one field's output direction)
        for b in &self.fields {
            for a in 0..b.n_out {
                acc.fill(0.0);
                for i in 0..b.spread.1 - b.spread.0 {
                    let w = b.u[i * b.n_out + a];
                    let ti = &t[(b.spread.0 + i) * width..(b.spread.0 + i + 1) * width];
                    for (acc, t) in acc.iter_mut().zip(ti) {
                        *acc += w * t;
                    }
                }
                for (c, &v) in acc.iter().enumerate() {
                    out[(b.spread_at + a, c)] = v;
                }
            }
        }
    }
}

/// The eigenvectors (ascending eigenvalues) of the sum of `blocks` (each `n × n`, each
/// normalized to its largest eigenvalue; zero blocks left out) and how many of them lie
/// above `tol²`; `None` when an eigenvalue problem fails.
fn directions(blocks: &[Mat<f64>], n: usize, tol: f64) -> Option<(Mat<f64>, usize)> {
    let mut sum = Mat::<f64>::zeros(n, n);
    if n == 0 {
        return Some((sum, 0));
    }
    for b in blocks {
        let top = b
            .self_adjoint_eigenvalues(Side::Lower)
            .ok()?
            .last()
            .copied()
            .unwrap_or(0.0);
        if top > 0.0 && top.is_finite() {
            sum += b * (1.0 / top);
        }
    }
    let eig = sum.self_adjoint_eigen(Side::Lower).ok()?;
    let s = eig.S();
    let kept = (0..n).filter(|&i| s[i] > tol * tol).count();
    Some((eig.U().to_owned(), kept))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::StateSpace;
    use crate::systems::chain::Chain;

    /// Fluctuations built with known ranges (rank 1 in the mechanical block, rank 2 in the
    /// thermal one, nothing across): the bases have those ranks, and `U (Uᵀ D V) Vᵀ`
    /// gives every interval's `D` back to rounding.
    #[test]
    fn the_bases_span_the_ranges_of_constructed_fluctuations() {
        let sys = Chain::with_contacts(6, 5, 3, 4);
        let full = StateSpace::new(&sys, 0.9).expect("state space");
        let space = full.with_velocity_gather(false);
        let (p, q) = (space.dofs().mech.len(), space.dofs().therm.len());
        assert!(p >= 2 && q >= 3, "the test needs room for the ranks");
        let (g, r) = space.low_rank_dims();
        let vecs = |n: usize, s: f64| {
            (0..n)
                .map(|i| (s * (i + 1) as f64).sin())
                .collect::<Vec<_>>()
        };
        let (a, b) = (vecs(p, 0.7), vecs(p, 1.3));
        let (e, f, h, w) = (vecs(q, 0.4), vecs(q, 2.1), vecs(q, 0.9), vecs(q, 1.7));
        let evals: Vec<NonlinearEval> = (0..12)
            .map(|k| {
                let (c, d, s) = (
                    (0.3 * k as f64).cos(),
                    1.0 + 0.1 * k as f64,
                    (0.5 * k as f64).sin(),
                );
                let mut m = NonlinearEval::new(p, q);
                // row-major outer products
                for (at, v) in m.df_dx.iter_mut().enumerate() {
                    *v = 1e8 * c * a[at / p] * b[at % p];
                }
                for (at, v) in m.dg_dt.iter_mut().enumerate() {
                    let (i, j) = (at / q, at % q);
                    *v = d * e[i] * f[j] + s * h[i] * w[j];
                }
                m
            })
            .collect();
        let means = SparseMeans::from_dense(&space, &evals);
        let zero = NonlinearEval::new(p, q);
        let layout = means.layout(&space);
        let ranges = [((0, p), (0, p)), ((p, g), (p, r))];
        let basis =
            KickBasis::new(&means, &zero, &layout, &ranges, r, 1e-6).expect("directions to drop");
        assert_eq!(basis.ranges(0), ((0, 1), (0, 1)));
        assert_eq!(basis.ranges(1), ((1, 3), (1, 3)));
        let (vm, um) = basis.bases(0);
        let (vt, ut) = basis.bases(1);
        let mut v = Mat::<f64>::zeros(g, 3);
        let mut u = Mat::<f64>::zeros(r, 3);
        v.as_mut().submatrix_mut(0, 0, p, 1).copy_from(&vm);
        v.as_mut().submatrix_mut(p, 1, q, 2).copy_from(&vt);
        u.as_mut().submatrix_mut(0, 0, p, 1).copy_from(&um);
        u.as_mut().submatrix_mut(p, 1, q, 2).copy_from(&ut);
        let mut t = basis.scratch();
        let mut dk = Mat::<f64>::zeros(3, 3);
        for (k, m) in evals.iter().enumerate() {
            basis.compress(means.row(k), &mut t, dk.as_mut());
            let mut want = Mat::<f64>::zeros(r, g);
            space.derivative_matrix(m, want.as_mut());
            let back = &u * &dk * v.transpose();
            for (rows, cols) in [((0, p), (0, p)), ((p, r), (p, g))] {
                let scale = want
                    .as_ref()
                    .submatrix(rows.0, cols.0, rows.1 - rows.0, cols.1 - cols.0)
                    .norm_max();
                let err = (back.as_ref() - want.as_ref())
                    .submatrix(rows.0, cols.0, rows.1 - rows.0, cols.1 - cols.0)
                    .norm_max();
                assert!(
                    err <= 1e-13 * scale,
                    "interval {k}, rows {rows:?}: {err:e} of {scale:e}"
                );
            }
        }
        // no tolerance: the products keep every row and column
        assert!(KickBasis::new(&means, &zero, &layout, &ranges, r, 0.0).is_none());
    }
}

//! The modal product on panels of [`W`] columns stored by rows.
//!
//! The same arithmetic as [`ExpSip::product_block_modal`] with the exponential interval
//! map, in another memory layout. A panel holds `W` columns of the product with each state
//! row's `W` entries side by side, so every operation of an interval (the gather, `G_k`,
//! the spread, the rotations of `e^{ΔΛ}`, the thermal field's updates) is a loop over
//! rows whose body is one `W`-wide multiply–add, and a row of a small matrix times a
//! panel reuses each loaded panel row for four output rows. The general matrix kernels do
//! the same products through one call per operation and interval (about ten thousand
//! calls per product on the dual rotor, each with its own dispatch and packing of the
//! small operands).
//!
//! A thread takes its block of columns (`by_column_blocks`, as the column-block product)
//! through all the intervals as a group of panels, so each interval's factor is read once
//! per group.

use faer::{Mat, MatMut, MatRef};

use super::{ExpSip, IntervalMap, Kicks, ModalField};
use crate::stability::modal::BlockDiagonal;
use crate::stability::sip::by_column_blocks;

/// Columns per panel.
pub(super) const W: usize = 8;

/// One state row of a panel.
type Row = [f64; W];

/// A dense matrix by columns without padding (`data[j·rows + i]`), the operand layout of
/// the panel kernels.
#[derive(Clone, Debug)]
pub(in crate::stability) struct Flat {
    rows: usize,
    cols: usize,
    data: Vec<f64>,
}

impl Flat {
    pub(super) fn zeros(rows: usize, cols: usize) -> Self {
        Self {
            rows,
            cols,
            data: vec![0.0; rows * cols],
        }
    }

    pub(super) fn from_mat(m: MatRef<'_, f64>) -> Self {
        let (rows, cols) = (m.nrows(), m.ncols());
        let mut data = Vec::with_capacity(rows * cols);
        for j in 0..cols {
            data.extend(m.col(j).iter().copied());
        }
        Self { rows, cols, data }
    }

    pub(super) fn as_mut(&mut self) -> MatMut<'_, f64> {
        MatMut::from_column_major_slice_mut(&mut self.data, self.rows, self.cols)
    }

    pub(super) fn as_ref(&self) -> MatRef<'_, f64> {
        MatRef::from_column_major_slice(&self.data, self.rows, self.cols)
    }

    /// Column `j` as a slice.
    pub(super) fn col_mut(&mut self, j: usize) -> &mut [f64] {
        &mut self.data[j * self.rows..(j + 1) * self.rows]
    }
}

/// `a·b + c`, fused where the target has the instruction (a library call otherwise).
#[inline(always)]
fn fma(a: f64, b: f64, c: f64) -> f64 {
    if cfg!(target_feature = "fma") {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

/// `out ← a x` (`add`: `out ← out + a x`) for panel rows `x` (`a.cols` of them) and `out`
/// (`a.rows`).
///
/// On a CPU with AVX-512 (checked once per process at run time) the rows go through
/// [`mul_avx512`], elsewhere through [`mul_portable`]: both do, for every output entry,
/// the same chain of fused multiply–adds in the same order, so their results are equal to
/// the last bit (unit test `the_avx512_kernel_equals_the_portable_one`).
fn mul(a: &Flat, x: &[Row], out: &mut [Row], add: bool) {
    #[cfg(target_arch = "x86_64")]
    if has_avx512() {
        // SAFETY: `mul_avx512` needs AVX-512F, and `has_avx512` found it on this CPU.
        #[allow(unsafe_code)]
        unsafe {
            mul_avx512(a, x, out, add)
        };
        return;
    }
    mul_portable(a, x, out, add);
}

/// Whether this CPU has AVX-512F (and the FMA the portable kernels use for the same
/// arithmetic); detected once, `TMROTOR_NO_AVX512` set to anything but `0` turns the
/// 512-bit kernels off (for comparisons).
#[cfg(target_arch = "x86_64")]
fn has_avx512() -> bool {
    use std::sync::OnceLock;
    static HAS: OnceLock<bool> = OnceLock::new();
    *HAS.get_or_init(|| {
        let off = std::env::var_os("TMROTOR_NO_AVX512").is_some_and(|v| v != "0");
        !off && cfg!(target_feature = "fma") && std::arch::is_x86_feature_detected!("avx512f")
    })
}

/// The instruction set the panel products run with on this CPU, for time reports:
/// `"AVX-512"` where the 512-bit kernel is used, else the build's own vector width on
/// x86-64 (`"AVX2"` or `"SSE2"`), or `"portable"` elsewhere.
pub(super) fn kernel_isa() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    {
        if has_avx512() {
            "AVX-512"
        } else if cfg!(target_feature = "avx2") {
            "AVX2"
        } else {
            "SSE2"
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        "portable"
    }
}

/// [`mul`] in the build's own instruction set: output rows four at a time (eight
/// accumulators of four doubles on AVX2), the rest two and one at a time.
fn mul_portable(a: &Flat, x: &[Row], out: &mut [Row], add: bool) {
    mul_in_blocks::<4>(a, x, out, add);
}

/// [`mul`] compiled for AVX-512: output rows eight at a time, so that each of the eight
/// accumulators is one 512-bit register (a panel row is eight doubles) and each loaded
/// panel row serves eight output rows; the rest four, two and one at a time.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
fn mul_avx512(a: &Flat, x: &[Row], out: &mut [Row], add: bool) {
    mul_in_blocks::<8>(a, x, out, add);
}

/// Output rows in blocks of `B` (8 or 4), then the rest by halves down to one.
#[inline(always)]
fn mul_in_blocks<const B: usize>(a: &Flat, x: &[Row], out: &mut [Row], add: bool) {
    let m = a.rows;
    debug_assert_eq!(x.len(), a.cols);
    debug_assert_eq!(out.len(), m);
    let mut i = 0;
    while i + B <= m {
        rows_of::<B>(a, x, out, i, add);
        i += B;
    }
    if B > 4 && i + 4 <= m {
        rows_of::<4>(a, x, out, i, add);
        i += 4;
    }
    if i + 2 <= m {
        rows_of::<2>(a, x, out, i, add);
        i += 2;
    }
    if i < m {
        rows_of::<1>(a, x, out, i, add);
    }
}

/// Output rows `i..i + R` of [`mul`]: each loaded panel row `x[j]` serves `R` rows.
#[inline(always)]
fn rows_of<const R: usize>(a: &Flat, x: &[Row], out: &mut [Row], i: usize, add: bool) {
    let mut acc = [[0.0; W]; R];
    if add {
        acc.copy_from_slice(&out[i..i + R]);
    }
    for (col, xj) in a.data.chunks_exact(a.rows).zip(x) {
        let c = &col[i..i + R];
        for (acc_r, &c_r) in acc.iter_mut().zip(c) {
            for (s, &v) in acc_r.iter_mut().zip(xj) {
                *s = fma(c_r, v, *s);
            }
        }
    }
    out[i..i + R].copy_from_slice(&acc);
}

/// [`mul`] on `N` panels with the same `a`: `ios[p] = (x, out)` of panel `p`. On a CPU with
/// AVX-512 two panels go through [`mul_pair_avx512`] together, so that each broadcast
/// entry of `a` feeds two 512-bit multiply–adds (with one panel each feeds one; the AVX2
/// kernel feeds two already, a row being two of its registers); elsewhere, and for a
/// panel left over, [`mul`] per panel. The same fused multiply–adds in the same order for
/// every entry either way.
fn mul_n<const N: usize>(a: &Flat, ios: [(&[Row], &mut [Row]); N], add: bool) {
    #[cfg(target_arch = "x86_64")]
    if N == 2 && has_avx512() {
        let mut it = ios.into_iter();
        if let (Some((x1, o1)), Some((x2, o2))) = (it.next(), it.next()) {
            // SAFETY: `mul_pair_avx512` needs AVX-512F and FMA; `has_avx512` found both.
            #[allow(unsafe_code)]
            unsafe {
                mul_pair_avx512(a, [x1, x2], [o1, o2], add)
            };
        }
        return;
    }
    for (x, out) in ios {
        mul(a, x, out, add);
    }
}

/// [`mul`] on two panels at once, compiled for AVX-512: output rows four at a time, each
/// with one accumulator register per panel (eight in all), each broadcast entry of `a`
/// used for both panels; the rest two and one at a time.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
fn mul_pair_avx512(a: &Flat, x: [&[Row]; 2], out: [&mut [Row]; 2], add: bool) {
    let m = a.rows;
    debug_assert!(x.iter().all(|x| x.len() == a.cols));
    debug_assert!(out.iter().all(|o| o.len() == m));
    let [o1, o2] = out;
    let mut i = 0;
    while i + 4 <= m {
        pair_rows_of::<4>(a, x, [&mut *o1, &mut *o2], i, add);
        i += 4;
    }
    if i + 2 <= m {
        pair_rows_of::<2>(a, x, [&mut *o1, &mut *o2], i, add);
        i += 2;
    }
    if i < m {
        pair_rows_of::<1>(a, x, [o1, o2], i, add);
    }
}

/// Output rows `i..i + R` of [`mul_pair_avx512`] for both panels.
#[inline(always)]
fn pair_rows_of<const R: usize>(
    a: &Flat,
    x: [&[Row]; 2],
    out: [&mut [Row]; 2],
    i: usize,
    add: bool,
) {
    let mut acc = [[[0.0; W]; 2]; R];
    if add {
        for (r, acc_r) in acc.iter_mut().enumerate() {
            acc_r[0] = out[0][i + r];
            acc_r[1] = out[1][i + r];
        }
    }
    for ((col, x1), x2) in a.data.chunks_exact(a.rows).zip(x[0]).zip(x[1]) {
        let c = &col[i..i + R];
        for (acc_r, &c_r) in acc.iter_mut().zip(c) {
            for (s, &v) in acc_r[0].iter_mut().zip(x1) {
                *s = fma(c_r, v, *s);
            }
            for (s, &v) in acc_r[1].iter_mut().zip(x2) {
                *s = fma(c_r, v, *s);
            }
        }
    }
    let [o1, o2] = out;
    for (r, acc_r) in acc.iter().enumerate() {
        o1[i + r] = acc_r[0];
        o2[i + r] = acc_r[1];
    }
}

/// `y ← y + x`.
fn add_rows(y: &mut [Row], x: &[Row]) {
    for (yr, xr) in y.iter_mut().zip(x) {
        for (a, b) in yr.iter_mut().zip(xr) {
            *a += b;
        }
    }
}

/// One field's operands in the panel layout.
struct Field {
    rows: (usize, usize),
    gather: (usize, usize),
    spread: (usize, usize),
    /// `e^{ΔΛ}` of the field.
    full: BlockDiagonal,
    /// `S̃` (gathered rows × field rows) and `L̃` (field rows × spread columns).
    s: Flat,
    l: Flat,
}

/// The thermal field's block operands (see `SlowField`).
struct Slow {
    field: usize,
    block: usize,
    k01: Flat,
    sn: Flat,
    sn2: Flat,
    nl: Flat,
    exp_block: BlockDiagonal,
    /// `e^{nΔΛ}` for the shorter last block, when there is one.
    exp_last: Option<BlockDiagonal>,
}

/// The thermal field's state of one panel between two updates (see `SlowState`).
struct SlowRows {
    y: Vec<Row>,
    a1: Vec<Row>,
    a2: Vec<Row>,
    /// `[u_n; U_n]`.
    stack: Vec<Row>,
    v: Vec<Row>,
    n: usize,
}

/// One panel: its columns of the product, its gathered rows, `G_k`'s output and the
/// thermal field's block state (empty without a slow field).
struct Panel {
    prod: Vec<Row>,
    gathered: Vec<Row>,
    mixed: Vec<Row>,
    slow: SlowRows,
}

/// Everything the intervals apply, shared by the panels.
struct Plan<'p> {
    fields: Vec<Field>,
    slow: Option<Slow>,
    factors: &'p [Flat],
}

impl ExpSip {
    /// The product of [`Self::product_block_modal`] (exponential map) on panels, all
    /// columns, in the modal coordinates; `None` when it does not apply (another map, or
    /// nothing gathered).
    pub(super) fn modal_product_panels(
        space: &crate::integrate::StateSpace<'_>,
        factors: &[Flat],
        fields: &[ModalField],
        kicks: &Kicks,
    ) -> Option<Mat<f64>> {
        let (g, r) = (kicks.k.nrows(), kicks.k.ncols());
        if kicks.map != IntervalMap::Exponential || r == 0 || g == 0 {
            return None;
        }
        let plan = Plan::new(fields, kicks, factors);
        let d = space.dim();
        Some(by_column_blocks(d, |c0, c1| plan.run(d, g, r, c0, c1)))
    }
}

impl<'p> Plan<'p> {
    fn new(fields: &[ModalField], kicks: &Kicks, factors: &'p [Flat]) -> Self {
        let fields_p = fields
            .iter()
            .enumerate()
            .map(|(i, f)| Field {
                rows: f.rows,
                gather: f.gather,
                spread: f.spread,
                full: kicks.exps[i][1].clone(),
                s: Flat::from_mat(kicks.gather[i].as_ref()),
                l: Flat::from_mat(kicks.spread[i].as_ref()),
            })
            .collect();
        let slow = kicks.slow.as_ref().map(|s| {
            let n = factors.len();
            let last = (n + s.block - 1) % s.block + 1;
            Slow {
                field: s.field,
                block: s.block,
                k01: Flat::from_mat(s.k01.as_ref()),
                sn: Flat::from_mat(s.sn.as_ref()),
                sn2: Flat::from_mat(s.sn2.as_ref()),
                nl: Flat::from_mat(s.nl.as_ref()),
                exp_block: s.exp_block.clone(),
                exp_last: (last != s.block)
                    .then(|| fields[s.field].modal.exp(last as f64 * kicks.delta)),
            }
        });
        Self {
            fields: fields_p,
            slow,
            factors,
        }
    }

    /// Columns `c0..c1` through all the intervals, on panels of `W` of them (the last one
    /// padded).
    fn run(&self, d: usize, g: usize, r: usize, c0: usize, c1: usize) -> Mat<f64> {
        let mut panels: Vec<Panel> = (c0..c1)
            .step_by(W)
            .map(|p0| {
                let mut prod = vec![[0.0; W]; d];
                for (l, c) in (p0..c1.min(p0 + W)).enumerate() {
                    prod[c][l] = 1.0;
                }
                let mut slow = SlowRows::empty(0);
                if let Some(s) = self.slow.as_ref() {
                    let f = &self.fields[s.field];
                    slow = SlowRows::empty(f.gather.1 - f.gather.0);
                    slow.restart(s, f, &prod[f.rows.0..f.rows.1]);
                }
                Panel {
                    prod,
                    gathered: vec![[0.0; W]; g],
                    mixed: vec![[0.0; W]; r],
                    slow,
                }
            })
            .collect();
        let last = self.factors.len().saturating_sub(1);
        for (k, gk) in self.factors.iter().enumerate() {
            // two panels at a time (see `mul_n`), a last odd one alone
            let mut pairs = panels.chunks_exact_mut(2);
            for pair in &mut pairs {
                if let [p1, p2] = pair {
                    self.interval([p1, p2], k == last, gk);
                }
            }
            for panel in pairs.into_remainder() {
                self.interval([panel], k == last, gk);
            }
        }
        Mat::from_fn(d, c1 - c0, |i, j| panels[j / W].prod[i][j % W])
    }

    /// One interval of `N` panels: `prod ← e^{ΔΛ} prod + L̃ G_k S̃ prod`, the thermal
    /// field by its block update; each panel as on its own, the products of the panels
    /// with the same matrix taken together ([`mul_n`]).
    fn interval<const N: usize>(&self, panels: [&mut Panel; N], last: bool, gk: &Flat) {
        let slow_index = self.slow.as_ref().map(|s| s.field);
        let mut parts = panels.map(|p| {
            let Panel {
                prod,
                gathered,
                mixed,
                slow,
            } = p;
            (
                prod.as_mut_slice(),
                gathered.as_mut_slice(),
                mixed.as_mut_slice(),
                slow,
            )
        });
        for (i, f) in self.fields.iter().enumerate() {
            if f.gather.1 <= f.gather.0 {
                continue;
            }
            let (g0, g1) = f.gather;
            if Some(i) == slow_index {
                for (_, gathered, _, st) in &mut parts {
                    gathered[g0..g1].copy_from_slice(&st.y);
                }
            } else {
                let (r0, r1) = f.rows;
                let ios = parts
                    .each_mut()
                    .map(|(prod, gathered, _, _)| (&prod[r0..r1], &mut gathered[g0..g1]));
                mul_n(&f.s, ios, false);
            }
        }
        let ios = parts
            .each_mut()
            .map(|(_, gathered, mixed, _)| (&**gathered, &mut **mixed));
        mul_n(gk, ios, false);
        for (i, f) in self.fields.iter().enumerate() {
            if Some(i) == slow_index {
                continue;
            }
            let (r0, r1) = f.rows;
            for (prod, _, _, _) in &mut parts {
                f.full.apply_rows(&mut prod[r0..r1]);
            }
            if f.spread.1 > f.spread.0 {
                let (s0, s1) = f.spread;
                let ios = parts
                    .each_mut()
                    .map(|(prod, _, mixed, _)| (&mixed[s0..s1], &mut prod[r0..r1]));
                mul_n(&f.l, ios, true);
            }
        }
        if let Some(s) = self.slow.as_ref() {
            let f = &self.fields[s.field];
            let (s0, s1) = f.spread;
            for (_, _, mixed, st) in &mut parts {
                st.start_advance(&mixed[s0..s1]);
            }
            let ios = parts.each_mut().map(|(_, _, _, st)| st.kick_operands());
            mul_n(&s.k01, ios, true);
            for (prod, _, _, st) in &mut parts {
                st.end_advance();
                if st.n == s.block || last {
                    let rows = &mut prod[f.rows.0..f.rows.1];
                    st.finish(s, f, rows);
                    if !last {
                        st.restart(s, f, rows);
                    }
                }
            }
        }
    }
}

impl SlowRows {
    /// Starts a block from the field's rows `t`: `y = S̃ t`, `a₁ = S̃N t`, `a₂ = S̃N² t`.
    fn restart(&mut self, s: &Slow, f: &Field, t: &[Row]) {
        mul(&f.s, t, &mut self.y, false);
        mul(&s.sn, t, &mut self.a1, false);
        mul(&s.sn2, t, &mut self.a2, false);
        self.stack.iter_mut().for_each(|r| *r = [0.0; W]);
        self.v.iter_mut().for_each(|r| *r = [0.0; W]);
        self.n = 0;
    }

    /// Zeroed rows for a field of `q` gathered temperatures (`q = 0`: no slow field).
    fn empty(q: usize) -> Self {
        Self {
            y: vec![[0.0; W]; q],
            a1: vec![[0.0; W]; q],
            a2: vec![[0.0; W]; q],
            stack: vec![[0.0; W]; 2 * q],
            v: vec![[0.0; W]; q],
            n: 0,
        }
    }

    /// One interval with kick `u`:
    /// `y ← y + S̃N t₀ + n S̃N² t₀ + K₀ u + K₁ U`, then `V ← V + U`, `U ← U + u`; in
    /// three parts so that the product with `[K₀ K₁]` can take several panels at once:
    /// this one, `y ← y + [K₀ K₁] [u; U]` on [`Self::kick_operands`], and
    /// [`Self::end_advance`].
    fn start_advance(&mut self, u: &[Row]) {
        let q = self.y.len();
        self.stack[..q].copy_from_slice(u);
        let n = self.n as f64;
        for ((y, a1), a2) in self.y.iter_mut().zip(&self.a1).zip(&self.a2) {
            for l in 0..W {
                y[l] += a1[l] + n * a2[l];
            }
        }
    }

    /// `([u; U], y)`: the operands of the interval's product with `[K₀ K₁]`.
    fn kick_operands(&mut self) -> (&[Row], &mut [Row]) {
        (&self.stack, &mut self.y)
    }

    /// The end of an interval (see [`Self::start_advance`]): `V ← V + U`, `U ← U + u`.
    fn end_advance(&mut self) {
        let q = self.y.len();
        let (kick, sum) = self.stack.split_at_mut(q);
        add_rows(&mut self.v, sum);
        add_rows(sum, kick);
        self.n += 1;
    }

    /// Brings the field's rows `t` to the end of the block:
    /// `t ← e^{nΔΛ} t + L̃ U + N L̃ V`.
    fn finish(&self, s: &Slow, f: &Field, t: &mut [Row]) {
        let q = self.y.len();
        match (&s.exp_last, self.n == s.block) {
            (Some(e), false) => e.apply_rows(t),
            _ => s.exp_block.apply_rows(t),
        }
        mul(&f.l, &self.stack[q..], t, true);
        mul(&s.nl, &self.v, t, true);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `m × k` matrix, `k` panel rows and `m` output rows of made-up values.
    fn operands(m: usize, k: usize) -> (Mat<f64>, Mat<f64>, Mat<f64>) {
        let a = Mat::from_fn(m, k, |i, j| (i as f64 + 1.0) * 0.3 - j as f64 * 0.7);
        let x = Mat::from_fn(k, W, |i, j| ((i * W + j) as f64).sin());
        let c = Mat::from_fn(m, W, |i, j| ((i + 2 * j) as f64).cos());
        (a, x, c)
    }

    fn rows(b: &Mat<f64>) -> Vec<Row> {
        (0..b.nrows())
            .map(|i| std::array::from_fn(|l| b[(i, l)]))
            .collect()
    }

    /// `got` equals `want` to the last bit, entry by entry.
    fn assert_same_bits(want: &[Row], got: &[Row], case: &str) {
        assert_eq!(want.len(), got.len(), "{case}");
        for (i, (p, w)) in want.iter().zip(got).enumerate() {
            for l in 0..W {
                assert_eq!(
                    p[l].to_bits(),
                    w[l].to_bits(),
                    "{case}: ({i}, {l}) {} against {}",
                    w[l],
                    p[l]
                );
            }
        }
    }

    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_avx512_kernel_equals_the_portable_one() {
        if !has_avx512() {
            eprintln!("this CPU has no AVX-512: nothing to compare");
            return;
        }
        // every row count from 0 to 19 (the blocks of eight, four, two and the last row)
        for m in 0..20 {
            let (a, x, c) = operands(m, 13);
            let flat = Flat::from_mat(a.as_ref());
            for add in [false, true] {
                let mut portable = rows(&c);
                mul_portable(&flat, &rows(&x), &mut portable, add);
                let mut wide = rows(&c);
                // SAFETY: `has_avx512` found AVX-512F on this CPU.
                #[allow(unsafe_code)]
                unsafe {
                    mul_avx512(&flat, &rows(&x), &mut wide, add)
                };
                assert_same_bits(&portable, &wide, &format!("m = {m}, add = {add}"));
            }
        }
    }

    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_avx512_pair_kernel_equals_the_portable_one() {
        if !has_avx512() {
            eprintln!("this CPU has no AVX-512: nothing to compare");
            return;
        }
        // every row count from 0 to 19 (the blocks of four, two and the last row)
        for m in 0..20 {
            let (a, x, c) = operands(m, 11);
            let (_, y, e) = operands(m, 11);
            // a second panel of other values
            let y = Mat::from_fn(y.nrows(), W, |i, j| y[(i, j)] * 1.7 - 0.2);
            let e = Mat::from_fn(e.nrows(), W, |i, j| e[(i, j)] + 0.3);
            let flat = Flat::from_mat(a.as_ref());
            for add in [false, true] {
                let (mut p1, mut p2) = (rows(&c), rows(&e));
                mul_portable(&flat, &rows(&x), &mut p1, add);
                mul_portable(&flat, &rows(&y), &mut p2, add);
                let (mut w1, mut w2) = (rows(&c), rows(&e));
                let (rx, ry) = (rows(&x), rows(&y));
                mul_n(&flat, [(&rx[..], &mut w1[..]), (&ry[..], &mut w2[..])], add);
                for (want, got) in [(&p1, &w1), (&p2, &w2)] {
                    assert_same_bits(want, got, &format!("m = {m}, add = {add}"));
                }
            }
        }
    }

    #[test]
    fn the_panel_kernel_equals_the_dense_product() {
        // every row count from 0 to 19 (the row blocks and the rest), both modes
        for m in 0..20 {
            let (a, x, c) = operands(m, 7);
            let flat = Flat::from_mat(a.as_ref());
            for add in [false, true] {
                let mut out = rows(&c);
                mul(&flat, &rows(&x), &mut out, add);
                let want = if add { &c + &a * &x } else { &a * &x };
                for (i, row) in out.iter().enumerate() {
                    for (l, &v) in row.iter().enumerate() {
                        assert!(
                            (v - want[(i, l)]).abs() < 1e-12 * (1.0 + want[(i, l)].abs()),
                            "m = {m}, add = {add}: ({i}, {l}) {v} against {}",
                            want[(i, l)]
                        );
                    }
                }
            }
        }
    }
}

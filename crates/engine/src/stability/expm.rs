//! Matrix exponential by scaling and squaring with the [13/13] Padé approximant
//! (Higham, "The scaling and squaring method for the matrix exponential revisited",
//! SIAM J. Matrix Anal. Appl. 26(4), 2005, Algorithm 2.3, the `m = 13` branch).
//!
//! The state matrices of rotor models mix units (m, m/s, K) and scales (`k/m ~ 10⁹ 1/s²`
//! next to 1); before scaling, the matrix is balanced by a diagonal similarity with powers
//! of two (Parlett & Reinsch, Numer. Math. 13, 1969), which leaves the exponential exact
//! (`e^{D⁻¹AD} = D⁻¹ e^A D`) and lowers the norm that decides the number of squarings.

use faer::Mat;
use faer::linalg::solvers::Solve;

/// Padé [13/13] numerator coefficients `b_0..b_13` (Higham 2005, Table 2.3 context).
const B13: [f64; 14] = [
    64_764_752_532_480_000.0,
    32_382_376_266_240_000.0,
    7_771_770_303_897_600.0,
    1_187_353_796_428_800.0,
    129_060_195_264_000.0,
    10_559_470_521_600.0,
    670_442_572_800.0,
    33_522_128_640.0,
    1_323_241_920.0,
    40_840_800.0,
    960_960.0,
    16_380.0,
    182.0,
    1.0,
];

/// `θ_13`: largest 1-norm for which the [13/13] approximant is accurate to unit roundoff.
const THETA13: f64 = 5.371_920_351_148_152;

fn norm1(a: &Mat<f64>) -> f64 {
    (0..a.ncols())
        .map(|j| a.col(j).iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// Diagonal balancing with powers of two; returns the scale `d` with `A ← D⁻¹ A D`.
pub(crate) fn balance(a: &mut Mat<f64>) -> Vec<f64> {
    let n = a.nrows();
    let mut d = vec![1.0; n];
    for _sweep in 0..32 {
        let mut converged = true;
        for i in 0..n {
            let c: f64 = (0..n).filter(|&k| k != i).map(|k| a[(k, i)].abs()).sum();
            let r: f64 = (0..n).filter(|&k| k != i).map(|k| a[(i, k)].abs()).sum();
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let s = c + r;
            let mut f = 1.0;
            let (mut cc, mut rr) = (c, r);
            while cc < rr / 2.0 {
                cc *= 2.0;
                rr /= 2.0;
                f *= 2.0;
            }
            while cc >= rr * 2.0 {
                cc /= 2.0;
                rr *= 2.0;
                f /= 2.0;
            }
            if (cc + rr) < 0.95 * s {
                converged = false;
                d[i] *= f;
                // A ← D_i⁻¹ A D_i with D_i = diag(.., f, ..): row i / f, column i × f.
                for k in 0..n {
                    a[(i, k)] /= f;
                    a[(k, i)] *= f;
                }
            }
        }
        if converged {
            break;
        }
    }
    d
}

/// `e^A` for a square matrix `A`. Returns `None` when `A` has non-finite entries or the
/// Padé denominator cannot be solved (which does not happen for finite input).
pub fn expm(a: &Mat<f64>) -> Option<Mat<f64>> {
    let n = a.nrows();
    if a.ncols() != n {
        return None;
    }
    if a.col_iter().any(|c| c.iter().any(|v| !v.is_finite())) {
        return None;
    }
    if n == 0 {
        return Some(Mat::zeros(0, 0));
    }
    let mut ab = a.clone();
    let d = balance(&mut ab);
    let norm = norm1(&ab);
    let s = if norm > THETA13 {
        (norm / THETA13).log2().ceil() as i32
    } else {
        0
    };
    let scale = 0.5f64.powi(s);
    let a1 = Mat::from_fn(n, n, |i, j| ab[(i, j)] * scale);
    let ident = Mat::<f64>::identity(n, n);
    let a2 = &a1 * &a1;
    let a4 = &a2 * &a2;
    let a6 = &a4 * &a2;
    let b = &B13;
    let u_inner = Mat::from_fn(n, n, |i, j| {
        b[13] * a6[(i, j)] + b[11] * a4[(i, j)] + b[9] * a2[(i, j)]
    });
    let u_tail = Mat::from_fn(n, n, |i, j| {
        b[7] * a6[(i, j)] + b[5] * a4[(i, j)] + b[3] * a2[(i, j)] + b[1] * ident[(i, j)]
    });
    let u = &a1 * (&a6 * &u_inner + &u_tail);
    let v_inner = Mat::from_fn(n, n, |i, j| {
        b[12] * a6[(i, j)] + b[10] * a4[(i, j)] + b[8] * a2[(i, j)]
    });
    let v_tail = Mat::from_fn(n, n, |i, j| {
        b[6] * a6[(i, j)] + b[4] * a4[(i, j)] + b[2] * a2[(i, j)] + b[0] * ident[(i, j)]
    });
    let v = &a6 * &v_inner + &v_tail;
    let p = &v + &u;
    let q = &v - &u;
    let mut r = q.partial_piv_lu().solve(&p);
    for _ in 0..s {
        r = &r * &r;
    }
    // Undo the balancing: e^A = D e^{D⁻¹AD} D⁻¹.
    let out = Mat::from_fn(n, n, |i, j| r[(i, j)] * d[i] / d[j]);
    let finite = out.col_iter().all(|c| c.iter().all(|v| v.is_finite()));
    finite.then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn max_diff(a: &Mat<f64>, b: &Mat<f64>) -> f64 {
        let mut m = 0.0f64;
        for i in 0..a.nrows() {
            for j in 0..a.ncols() {
                m = m.max((a[(i, j)] - b[(i, j)]).abs());
            }
        }
        m
    }

    #[test]
    fn damped_oscillator_matches_closed_form() {
        // ẍ + 2ζω ẋ + ω² x = 0, underdamped: exact transition matrix over time t.
        let (w, z, t) = (3.0f64, 0.1f64, 2.7f64);
        let a = Mat::from_fn(2, 2, |i, j| match (i, j) {
            (0, 1) => t,
            (1, 0) => -w * w * t,
            (1, 1) => -2.0 * z * w * t,
            _ => 0.0,
        });
        let wd = w * (1.0 - z * z).sqrt();
        let e = (-z * w * t).exp();
        let (c, s) = ((wd * t).cos(), (wd * t).sin());
        let exact = Mat::from_fn(2, 2, |i, j| match (i, j) {
            (0, 0) => e * (c + z * w / wd * s),
            (0, 1) => e * s / wd,
            (1, 0) => -e * w * w / wd * s,
            _ => e * (c - z * w / wd * s),
        });
        let got = expm(&a).expect("finite");
        assert!(max_diff(&got, &exact) < 1e-13, "{got:?} vs {exact:?}");
    }

    #[test]
    fn stiff_and_badly_scaled_diagonalisable_matrix() {
        // A = S diag(λ) S⁻¹ with λ from −1e6 to −0.5 and S mixing very different scales.
        let lam = [-1.0e6, -3.0e3, -0.5, -20.0];
        let s = Mat::from_fn(4, 4, |i, j| {
            let base = [
                [1.0, 0.2, 0.0, 0.3],
                [0.0, 1.0, 0.4, 0.0],
                [0.1, 0.0, 1.0, 0.2],
                [0.0, 0.3, 0.0, 1.0],
            ][i][j];
            base * [1.0, 1e4, 1e-3, 1.0][i]
        });
        let sinv = s.partial_piv_lu().solve(Mat::<f64>::identity(4, 4));
        let a = &s * Mat::from_fn(4, 4, |i, j| if i == j { lam[i] } else { 0.0 }) * &sinv;
        let exact = &s * Mat::from_fn(4, 4, |i, j| if i == j { lam[i].exp() } else { 0.0 }) * &sinv;
        let got = expm(&a).expect("finite");
        for i in 0..4 {
            for j in 0..4 {
                let tol = 1e-10 * exact[(i, j)].abs().max(1e-6 * norm1(&exact));
                assert!(
                    (got[(i, j)] - exact[(i, j)]).abs() <= tol,
                    "({i},{j}): {} vs {}",
                    got[(i, j)],
                    exact[(i, j)]
                );
            }
        }
    }

    #[test]
    fn inverse_is_exponential_of_negative() {
        let a = Mat::from_fn(5, 5, |i, j| {
            ((i * 7 + j * 3) % 5) as f64 - 2.0 + if i == j { -1.0 } else { 0.0 }
        });
        let neg = Mat::from_fn(5, 5, |i, j| -a[(i, j)]);
        let prod = expm(&a).expect("finite") * expm(&neg).expect("finite");
        assert!(max_diff(&prod, &Mat::identity(5, 5)) < 1e-11);
    }

    #[test]
    fn non_finite_input_is_refused() {
        let mut a = Mat::<f64>::zeros(2, 2);
        a[(0, 1)] = f64::NAN;
        assert!(expm(&a).is_none());
    }
}

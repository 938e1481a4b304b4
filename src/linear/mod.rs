//! Linear analyses of an assembled rotor: damped modes and the Campbell diagram.
//!
//! The linearised equations (paper Eq. 8 with the bearings replaced by their linearised
//! stiffness, [`crate::bearing::linear`]) at reference speed `ω`,
//!
//! ```text
//!   M q̈ + (C + Σ_r s_r ω G_r) q̇ + (K + K_b) q = 0,
//! ```
//!
//! are brought to a well-scaled state-space form: with the Cholesky factor `M = L Lᵀ`
//! and `y = Lᵀ q`, `ÿ + D̃ ẏ + K̃ y = 0` with `K̃ = L⁻¹(K+K_b)L⁻ᵀ` (symmetric unless a
//! support is cross-coupled) and
//! `D̃ = L⁻¹(C+ΣG)L⁻ᵀ`; the state `z = [y, S⁻¹ẏ]` with `S = diag(√K̃_ii)` gives
//! `A = [[0, S], [−S⁻¹K̃, −S⁻¹D̃S]]`, in which every DoF's 2×2 block is nearly normal
//! (`[[0, s_i], [−s_i, 0]]` for a diagonally dominant DoF). Rotor models mix light nodes
//! with stiff supports; the plain `[[0, I], [−M⁻¹K, −M⁻¹C]]` spans many decades and
//! loses the low modes to the largest entries. The
//! eigenvalues `λ = −ζ ω_n ± i ω_d` of `A` are computed with faer's dense nonsymmetric
//! eigensolver; mode shapes are `q = L⁻ᵀ y`. Each complex pair gives one
//! mode: damped natural frequency `ω_d = Im λ`, undamped `ω_n = |λ|`, damping ratio
//! `ζ = −Re λ / |λ|`, and the mode shape (the displacement half of the eigenvector,
//! scaled so that its largest entry is 1). Real eigenvalues (overdamped motion) are not
//! modes and are skipped. Modes are ordered by undamped frequency `|λ|`: stiffness-
//! proportional damping makes the highest FE modes overdamped (`ζ = a1 ω/2 ≥ 1` above
//! `2/a1`), and gyroscopic coupling gives such pairs a tiny imaginary part; ordered by
//! `|λ|` they stay at the end where they belong instead of posing as low-frequency modes.
//!
//! Whirl direction: with `q ∝ Re(φ e^{iω_d t})`, a node orbits from +x towards +y
//! (forward, the sense of rotation) when `Im(conj(φ_x) φ_y) < 0`. The sum over all nodes,
//! relative to `Σ |φ_x|² + |φ_y|²` (from the translations, or from the slopes when those
//! dominate), decides: below −1 % forward, above +1 % backward, otherwise planar
//! (a straight-line orbit, e.g. a degenerate pair at zero speed, where the split into
//! forward and backward is arbitrary).
//!
//! Campbell diagram: modes at a grid of speeds, sorted as above (mode `i` is the
//! `i`-th lowest at every speed), and critical speeds where a mode's frequency crosses an
//! excitation line `ω_exc = s_r ω` of each rotor (1× LP, 1× HP): bracketed by a sign
//! change between grid points, then located by regula falsi (Illinois) on fresh modal
//! solves, so the result does not depend on the grid spacing once the crossing is
//! bracketed. The whirl reported is that of the mode at the crossing.

mod unbalance;

pub use unbalance::{NodeOrbit, UnbalanceResponse, unbalance_response};

use faer::Mat;
use num_complex::Complex;
use thiserror::Error;

use crate::model::Assembly;
use crate::model::assembly::to_faer;

/// Errors of the linear analyses.
#[derive(Debug, Error)]
pub enum LinearError {
    /// The mass matrix could not be factorised.
    #[error("mass matrix is not positive definite (a DoF without mass?)")]
    SingularMass,
    /// The eigensolver did not converge.
    #[error("eigenvalue solver failed: {0}")]
    Eigen(String),
    /// A speed grid that cannot be used.
    #[error("bad speed grid: {0}")]
    BadSpeeds(String),
}

/// Whirl direction of a mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Whirl {
    /// Orbit in the sense of rotation (+x towards +y).
    Forward,
    /// Orbit against the sense of rotation.
    Backward,
    /// Straight-line orbit (no dominant sense).
    Planar,
}

impl Whirl {
    /// Lower-case name used in CSV output.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Forward => "forward",
            Self::Backward => "backward",
            Self::Planar => "planar",
        }
    }
}

impl std::fmt::Display for Whirl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One damped mode.
#[derive(Clone, Debug)]
pub struct Mode {
    /// Damped natural frequency `Im λ` (rad/s).
    pub frequency_rad_s: f64,
    /// Undamped natural frequency `|λ|` (rad/s).
    pub undamped_rad_s: f64,
    /// Damping ratio `−Re λ / |λ|`.
    pub damping_ratio: f64,
    /// The eigenvalue `λ` (1/s).
    pub eigenvalue: Complex<f64>,
    pub whirl: Whirl,
    /// Displacement part of the eigenvector (length `n_dof`), largest entry 1.
    pub shape: Vec<Complex<f64>>,
}

impl Mode {
    /// Damped natural frequency in Hz.
    pub fn frequency_hz(&self) -> f64 {
        self.frequency_rad_s / (2.0 * std::f64::consts::PI)
    }

    /// Logarithmic decrement `δ = −2π Re λ / Im λ` (the decay of the amplitude over one
    /// damped period: `ln(x_k / x_{k+1})`; negative for an unstable mode).
    pub fn log_decrement(&self) -> f64 {
        log_decrement(self.eigenvalue)
    }
}

/// Logarithmic decrement of the eigenvalue `λ`: `−2π Re λ / Im λ`.
pub fn log_decrement(lambda: Complex<f64>) -> f64 {
    -2.0 * std::f64::consts::PI * lambda.re / lambda.im
}

/// Whirl sense of a displacement shape (node-major `[x, y, θx, θy]`).
pub fn whirl_of(shape: &[Complex<f64>]) -> Whirl {
    let mut best = (0.0, 0.0);
    for off in [0, 2] {
        let (mut s, mut n) = (0.0, 0.0);
        for node in shape.chunks_exact(4) {
            let (px, py) = (node[off], node[off + 1]);
            s += (px.conj() * py).im;
            n += px.norm_sqr() + py.norm_sqr();
        }
        if n > best.1 {
            best = (s, n);
        }
    }
    let (s, n) = best;
    if n == 0.0 || (s / n).abs() < 0.01 {
        Whirl::Planar
    } else if s < 0.0 {
        Whirl::Forward
    } else {
        Whirl::Backward
    }
}

/// The `count` damped modes of lowest undamped frequency at reference speed `speed_rad_s` (rad/s), with the
/// linearised bearings included.
pub fn modes(asm: &Assembly, speed_rad_s: f64, count: usize) -> Result<Vec<Mode>, LinearError> {
    let lp = asm.linear_part_with_bearings(speed_rad_s);
    let n = asm.n_dof;
    let m = to_faer(&lp.mass);
    let llt = m
        .llt(faer::Side::Lower)
        .map_err(|_| LinearError::SingularMass)?;
    let l = llt.L();
    // X ↦ L⁻¹ X L⁻ᵀ, computed as (L⁻¹ (L⁻¹ X)ᵀ)ᵀ.
    let congruence = |x: Mat<f64>| -> Mat<f64> {
        let mut y = x;
        l.solve_lower_triangular_in_place(&mut y);
        let mut z = y.transpose().to_owned();
        l.solve_lower_triangular_in_place(&mut z);
        z.transpose().to_owned()
    };
    let k_t = congruence(to_faer(&lp.stiffness));
    let d_t = congruence(to_faer(&lp.damping));
    // Per-DoF velocity scaling s_i = √K̃_ii (1 where a DoF has no stiffness).
    let scale: Vec<f64> = (0..n)
        .map(|i| {
            let v = k_t[(i, i)].abs().sqrt();
            if v > 0.0 && v.is_finite() { v } else { 1.0 }
        })
        .collect();
    let a = Mat::from_fn(2 * n, 2 * n, |i, j| {
        if i < n {
            if j == i + n { scale[i] } else { 0.0 }
        } else if j < n {
            -k_t[(i - n, j)] / scale[i - n]
        } else {
            -d_t[(i - n, j - n)] * scale[j - n] / scale[i - n]
        }
    });
    if !a.col_iter().all(|c| c.iter().all(|v| v.is_finite())) {
        return Err(LinearError::Eigen("non-finite state matrix".into()));
    }
    let eig = a
        .eigen()
        .map_err(|e| LinearError::Eigen(format!("{e:?}")))?;
    let s = eig.S();
    let u = eig.U();
    let mut out = Vec::new();
    for k in 0..2 * n {
        let lam: Complex<f64> = s[k];
        if lam.im.is_nan() || lam.im <= 0.0 {
            continue;
        }
        // q = L⁻ᵀ y, real and imaginary parts separately.
        let mut re = Mat::from_fn(n, 1, |i, _| u[(i, k)].re);
        let mut im = Mat::from_fn(n, 1, |i, _| u[(i, k)].im);
        l.transpose().solve_upper_triangular_in_place(&mut re);
        l.transpose().solve_upper_triangular_in_place(&mut im);
        let mut shape: Vec<Complex<f64>> = (0..n)
            .map(|i| Complex::new(re[(i, 0)], im[(i, 0)]))
            .collect();
        let pivot = shape
            .iter()
            .copied()
            .max_by(|a, b| a.norm().total_cmp(&b.norm()))
            .unwrap_or(Complex::new(1.0, 0.0));
        if pivot.norm() > 0.0 {
            shape.iter_mut().for_each(|v| *v /= pivot);
        }
        let wn = lam.norm();
        out.push(Mode {
            frequency_rad_s: lam.im,
            undamped_rad_s: wn,
            damping_ratio: -lam.re / wn,
            eigenvalue: lam,
            whirl: whirl_of(&shape),
            shape,
        });
    }
    out.sort_by(|a, b| a.undamped_rad_s.total_cmp(&b.undamped_rad_s));
    out.truncate(count);
    Ok(out)
}

/// Frequencies of one speed of a Campbell diagram.
#[derive(Clone, Debug)]
pub struct CampbellPoint {
    pub speed_rad_s: f64,
    /// Modes sorted by frequency (shapes dropped).
    pub modes: Vec<ModeSummary>,
}

/// A mode without its shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModeSummary {
    pub frequency_rad_s: f64,
    pub damping_ratio: f64,
    pub whirl: Whirl,
}

/// A crossing of a mode with a rotor's 1× excitation line.
#[derive(Clone, Debug, PartialEq)]
pub struct CriticalSpeed {
    /// The exciting rotor's id.
    pub rotor_id: String,
    /// Its speed ratio (the line's slope).
    pub speed_ratio: f64,
    /// Mode number, 1-based, in order of frequency.
    pub mode: usize,
    /// Whirl of the mode at the crossing.
    pub whirl: Whirl,
    /// Reference speed ω at the crossing (rad/s).
    pub speed_rad_s: f64,
    /// Mode frequency at the crossing (rad/s) = speed_ratio × speed_rad_s.
    pub frequency_rad_s: f64,
}

/// A Campbell diagram.
#[derive(Clone, Debug)]
pub struct Campbell {
    pub points: Vec<CampbellPoint>,
    pub critical_speeds: Vec<CriticalSpeed>,
}

/// Locates the root of `g(ω) = f_i(ω) − s ω` in a bracket by the Illinois variant of
/// regula falsi (each evaluation is a modal solve), to 1e-10 relative in ω or 40
/// evaluations; returns the speed and the mode's whirl there.
fn refine_crossing(
    asm: &Assembly,
    i: usize,
    s: f64,
    (mut a, mut ga): (f64, f64),
    (mut b, mut gb): (f64, f64),
    count: usize,
) -> Result<(f64, Whirl), LinearError> {
    let eval = |w: f64| -> Result<Option<(f64, Whirl)>, LinearError> {
        let m = modes(asm, w, count)?;
        Ok(m.get(i).map(|m| (m.frequency_rad_s - s * w, m.whirl)))
    };
    if ga == 0.0 {
        let whirl = eval(a)?.map_or(Whirl::Planar, |x| x.1);
        return Ok((a, whirl));
    }
    let mut side = 0i8;
    let mut best = (0.5 * (a + b), Whirl::Planar);
    for _ in 0..40 {
        let w = (a * gb - b * ga) / (gb - ga);
        let Some((g, whirl)) = eval(w)? else {
            break;
        };
        best = (w, whirl);
        if g == 0.0 || (b - a).abs() <= 1e-10 * w.abs().max(1.0) {
            break;
        }
        if (g > 0.0) == (gb > 0.0) {
            b = w;
            gb = g;
            if side == -1 {
                ga *= 0.5;
            }
            side = -1;
        } else {
            a = w;
            ga = g;
            if side == 1 {
                gb *= 0.5;
            }
            side = 1;
        }
        if g.abs() <= 1e-12 * (s * w).abs().max(1.0) {
            break;
        }
    }
    Ok(best)
}

/// `count` evenly spaced speeds from `start` to `end` inclusive.
pub fn speed_grid(start: f64, end: f64, count: usize) -> Result<Vec<f64>, LinearError> {
    if !(start.is_finite() && end.is_finite()) || start < 0.0 || end <= start || count < 2 {
        return Err(LinearError::BadSpeeds(format!(
            "need 0 ≤ start < end and count ≥ 2, got {start}:{end}:{count}"
        )));
    }
    Ok((0..count)
        .map(|i| start + (end - start) * i as f64 / (count - 1) as f64)
        .collect())
}

/// Campbell diagram of the lowest `count` modes over `speeds` (rad/s, increasing), with
/// the critical speeds of every rotor's 1× line.
pub fn campbell(asm: &Assembly, speeds: &[f64], count: usize) -> Result<Campbell, LinearError> {
    if speeds.len() < 2 || speeds.windows(2).any(|w| w[1] <= w[0]) {
        return Err(LinearError::BadSpeeds(
            "need at least two strictly increasing speeds".into(),
        ));
    }
    let mut points = Vec::with_capacity(speeds.len());
    for &w in speeds {
        let ms = modes(asm, w, count)?;
        points.push(CampbellPoint {
            speed_rad_s: w,
            modes: ms
                .iter()
                .map(|m| ModeSummary {
                    frequency_rad_s: m.frequency_rad_s,
                    damping_ratio: m.damping_ratio,
                    whirl: m.whirl,
                })
                .collect(),
        });
    }
    let mut critical_speeds = Vec::new();
    let mut lines: Vec<(String, f64)> = Vec::new();
    for g in &asm.gyro {
        let s = g.speed_ratio.value();
        if !lines.iter().any(|(_, v)| *v == s) {
            lines.push((g.rotor_id.clone(), s));
        }
    }
    for (rotor_id, s) in &lines {
        for pair in points.windows(2) {
            let (p0, p1) = (&pair[0], &pair[1]);
            for i in 0..p0.modes.len().min(p1.modes.len()) {
                let g0 = p0.modes[i].frequency_rad_s - s * p0.speed_rad_s;
                let g1 = p1.modes[i].frequency_rad_s - s * p1.speed_rad_s;
                if g0 == 0.0 || (g0 > 0.0) != (g1 > 0.0) {
                    let (w, whirl) = refine_crossing(
                        asm,
                        i,
                        *s,
                        (p0.speed_rad_s, g0),
                        (p1.speed_rad_s, g1),
                        count,
                    )?;
                    critical_speeds.push(CriticalSpeed {
                        rotor_id: rotor_id.clone(),
                        speed_ratio: *s,
                        mode: i + 1,
                        whirl,
                        speed_rad_s: w,
                        frequency_rad_s: s * w,
                    });
                }
            }
        }
    }
    critical_speeds.sort_by(|a, b| a.speed_rad_s.total_cmp(&b.speed_rad_s));
    Ok(Campbell {
        points,
        critical_speeds,
    })
}

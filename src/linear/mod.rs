//! Linear analyses of an assembled rotor: damped modes and the Campbell diagram.
//!
//! The linearised equations (paper Eq. 8 with the bearings replaced by their linearised
//! stiffness, [`crate::model::bearing_linear`]) at reference speed `ω`,
//!
//! ```text
//!   M q̈ + (C + Σ_r s_r ω G_r) q̇ + (K + K_b) q = 0,
//! ```
//!
//! are written in state space `ż = A z`, `z = [q, q̇]`,
//! `A = [[0, I], [−M⁻¹(K+K_b), −M⁻¹(C+ΣG)]]`, and `A`'s eigenvalues `λ = −ζ ω_n ± i ω_d`
//! are computed with faer's dense nonsymmetric eigensolver. Each complex pair gives one
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
//! excitation line `ω_exc = s_r ω` of each rotor (1× LP, 1× HP), located by linear
//! interpolation between grid points.

use faer::Mat;
use faer::linalg::solvers::Solve;
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
    let minv_k = llt.solve(to_faer(&lp.stiffness));
    let minv_d = llt.solve(to_faer(&lp.damping));
    let a = Mat::from_fn(2 * n, 2 * n, |i, j| {
        if i < n {
            if j == i + n { 1.0 } else { 0.0 }
        } else if j < n {
            -minv_k[(i - n, j)]
        } else {
            -minv_d[(i - n, j - n)]
        }
    });
    let mut a = a;
    let scale = balance(&mut a);
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
        let mut shape: Vec<Complex<f64>> = (0..n).map(|i| u[(i, k)] * scale[i]).collect();
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

/// Diagonal balancing (Parlett & Reinsch, Numer. Math. 13 (1969) 293–304, as in LAPACK
/// `dgebal` without permutation): replaces `a` by `D⁻¹ a D` with `D` a diagonal of powers
/// of two chosen so that each row and column have similar norms, and returns `D`. The
/// eigenvalues are unchanged; an eigenvector `v` of the balanced matrix gives `D v`.
/// Rotor state matrices mix translations and rotations, and stiff supports with light
/// nodes, so their entries span many decades; without balancing the low modes lose
/// accuracy to the largest entries.
pub fn balance(a: &mut Mat<f64>) -> Vec<f64> {
    let n = a.nrows();
    let mut d = vec![1.0; n];
    let radix = 2.0_f64;
    for _sweep in 0..100 {
        let mut done = true;
        for i in 0..n {
            let (mut c, mut r) = (0.0, 0.0);
            for j in 0..n {
                if j != i {
                    c += a[(j, i)].abs();
                    r += a[(i, j)].abs();
                }
            }
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let total = c + r;
            let mut f = 1.0;
            let (mut cc, mut rr) = (c, r);
            while cc < rr / radix {
                cc *= radix;
                rr /= radix;
                f *= radix;
            }
            while cc >= rr * radix {
                cc /= radix;
                rr *= radix;
                f /= radix;
            }
            if (cc + rr) < 0.95 * total {
                done = false;
                d[i] *= f;
                for j in 0..n {
                    a[(i, j)] /= f;
                }
                for j in 0..n {
                    a[(j, i)] *= f;
                }
            }
        }
        if done {
            break;
        }
    }
    d
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
    /// Whirl of the mode at the grid point nearest the crossing.
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
                    let t = if g0 == g1 { 0.0 } else { g0 / (g0 - g1) };
                    let w = p0.speed_rad_s + t * (p1.speed_rad_s - p0.speed_rad_s);
                    let whirl = if t <= 0.5 {
                        p0.modes[i].whirl
                    } else {
                        p1.modes[i].whirl
                    };
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

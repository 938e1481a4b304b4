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
//! Campbell diagram: the lowest modes at the first speed of a grid, each followed from
//! speed to speed by its shape (the modal assurance criterion, [`mac`]), so that a mode
//! keeps its number where it crosses another in frequency or turns from forward to
//! backward whirl; critical speeds where a followed mode's frequency crosses an excitation
//! line `ω_exc = s_r ω` of each rotor (1× LP, 1× HP): bracketed by a sign change between
//! grid points, then located by regula falsi (Illinois) on fresh modal solves, so the
//! result does not depend on the grid spacing once the crossing is bracketed. Each
//! critical speed carries the mode's whirl and forward share at the crossing, which say
//! whether the rotor's unbalance (a forward force) excites it.
//!
//! Also here: the logarithmic decrement of each mode, and the unbalance response of the
//! linearised rotor ([`unbalance_response`]). Their figures and CSVs are drawn by the
//! commands (figures in the application's `figure::linear`, CSVs in `cli::linear_outputs`).

mod unbalance;

pub use unbalance::{NodeOrbit, UnbalanceResponse, unbalance_response};

use faer::Mat;
use num_complex::Complex;
use thiserror::Error;

use crate::model::assembly::to_faer;
use crate::model::{Assembly, DOF_PER_NODE};

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
    /// An unbalance response of a model without unbalance.
    #[error(
        "the model has no unbalance: give a disk an eccentricity (disks[i].eccentricity_m) to \
         compute an unbalance response"
    )]
    NoUnbalance,
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
    /// Displacement part of the eigenvector (length `n_dof`, node-major `[x, y, θx, θy]`),
    /// scaled by [`shape_pivot`]: the largest translation is 1 (phase 0), and the slopes
    /// carry the same factor (rad per unit of that translation).
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

/// The entry a mode shape is divided by: its largest translation (`x` or `y` of a node;
/// metres and radians are not compared), or its largest slope when it has no translation
/// (a pure tilt mode).
pub fn shape_pivot(shape: &[Complex<f64>]) -> Complex<f64> {
    let largest = |kind: std::ops::Range<usize>| {
        shape
            .chunks_exact(DOF_PER_NODE)
            .flat_map(|node| node[kind.clone()].iter().copied())
            .max_by(|a, b| a.norm().total_cmp(&b.norm()))
    };
    match largest(0..2) {
        Some(t) if t.norm() > 0.0 => t,
        _ => largest(2..4).unwrap_or(Complex::new(1.0, 0.0)),
    }
}

/// `Σ |X|² + |Y|²` of the translations (`off = 0`) or the slopes (`off = 2`) of a shape.
fn plane_energy(shape: &[Complex<f64>], off: usize) -> f64 {
    shape
        .chunks_exact(4)
        .map(|n| n[off].norm_sqr() + n[off + 1].norm_sqr())
        .sum()
}

/// Which pair of a shape's DoFs its whirl is judged on: the translations (0), or the
/// slopes (2) where those carry more; summed over `shapes`.
fn whirl_plane(shapes: &[&[Complex<f64>]]) -> usize {
    let energy = |off| shapes.iter().map(|s| plane_energy(s, off)).sum::<f64>();
    if energy(0) >= energy(2) { 0 } else { 2 }
}

/// Whirl sense of a displacement shape (node-major `[x, y, θx, θy]`).
pub fn whirl_of(shape: &[Complex<f64>]) -> Whirl {
    let off = whirl_plane(&[shape]);
    let s: f64 = shape
        .chunks_exact(4)
        .map(|node| (node[off].conj() * node[off + 1]).im)
        .sum();
    let n = plane_energy(shape, off);
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
        let pivot = shape_pivot(&shape);
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
    for k in 1..out.len() {
        let (a, b) = (out[k - 1].eigenvalue, out[k].eigenvalue);
        if (a - b).norm() <= DEGENERATE * a.norm().max(b.norm()) {
            let (left, right) = out.split_at_mut(k);
            split_whirl(&mut left[k - 1], &mut right[0]);
        }
    }
    out.truncate(count);
    Ok(out)
}

/// A degenerate pair (equal eigenvalues: any two independent combinations are its
/// shapes, e.g. a disk's translation at a node without tilt) rewritten as its most forward
/// and most backward combinations, the stationary values of [`forward_share`] on the
/// pair's plane: the 2×2 generalised Hermitian eigenproblem `F v = μ N v` with `F` the
/// forward and `N` the total whirl energy of the translations (or slopes). The more
/// forward one goes first.
fn split_whirl(a: &mut Mode, b: &mut Mode) {
    let i = Complex::new(0.0, 1.0);
    let off = whirl_plane(&[&a.shape, &b.shape]);
    // Hermitian forms over the pair: n[p][q] = Σ conj(u_p)·u_q, f likewise for the
    // forward parts (X + iY)/2.
    let shapes = [&a.shape, &b.shape];
    let mut n = [[Complex::new(0.0, 0.0); 2]; 2];
    let mut f = [[Complex::new(0.0, 0.0); 2]; 2];
    for p in 0..2 {
        for q in 0..2 {
            for (u, v) in shapes[p].chunks_exact(4).zip(shapes[q].chunks_exact(4)) {
                let (ux, uy, vx, vy) = (u[off], u[off + 1], v[off], v[off + 1]);
                n[p][q] += ux.conj() * vx + uy.conj() * vy;
                f[p][q] += (0.5 * (ux + i * uy)).conj() * (0.5 * (vx + i * vy));
            }
        }
    }
    // det(F − μN) = 0: a quadratic in μ with real roots (F, N Hermitian, N > 0).
    let det = |m: [[Complex<f64>; 2]; 2]| m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let qa = det(n).re;
    let qb = -(f[0][0] * n[1][1] + f[1][1] * n[0][0] - f[0][1] * n[1][0] - f[1][0] * n[0][1]).re;
    let qc = det(f).re;
    if qa.abs() < 1e-300 {
        return;
    }
    let disc = (qb * qb - 4.0 * qa * qc).max(0.0).sqrt();
    let roots = [(-qb + disc) / (2.0 * qa), (-qb - disc) / (2.0 * qa)];
    let combine = |mu: f64| -> Vec<Complex<f64>> {
        // (F − μN) v = 0: v = [m01, −m00] (or from the second row)
        let m00 = f[0][0] - mu * n[0][0];
        let m01 = f[0][1] - mu * n[0][1];
        let m10 = f[1][0] - mu * n[1][0];
        let m11 = f[1][1] - mu * n[1][1];
        let v = if m00.norm() + m01.norm() >= m10.norm() + m11.norm() {
            [m01, -m00]
        } else {
            [m11, -m10]
        };
        let mut w: Vec<Complex<f64>> = a
            .shape
            .iter()
            .zip(&b.shape)
            .map(|(x, y)| v[0] * x + v[1] * y)
            .collect();
        let pivot = w
            .iter()
            .copied()
            .max_by(|p, q| p.norm().total_cmp(&q.norm()))
            .unwrap_or(Complex::new(1.0, 0.0));
        if pivot.norm() > 0.0 {
            w.iter_mut().for_each(|x| *x /= pivot);
        }
        w
    };
    let (fw, bw) = (combine(roots[0]), combine(roots[1]));
    if fw
        .iter()
        .chain(&bw)
        .any(|v| !(v.re.is_finite() && v.im.is_finite()))
    {
        return;
    }
    a.shape = fw;
    b.shape = bw;
    a.whirl = whirl_of(&a.shape);
    b.whirl = whirl_of(&b.shape);
}

/// Frequencies of one speed of a Campbell diagram.
#[derive(Clone, Debug)]
pub struct CampbellPoint {
    pub speed_rad_s: f64,
    /// The followed modes at this speed: entry `i` is the same mode at every speed (see
    /// [`campbell`]), shapes dropped.
    pub modes: Vec<ModeSummary>,
}

/// A mode without its shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModeSummary {
    pub frequency_rad_s: f64,
    pub damping_ratio: f64,
    pub whirl: Whirl,
    /// Logarithmic decrement ([`log_decrement`]).
    pub log_decrement: f64,
    /// Share of forward whirl in the shape ([`forward_share`]).
    pub forward_share: f64,
    /// MAC of the shape with the same mode's shape at the previous speed (1 at the first
    /// speed): how sure the following is.
    pub mac: f64,
}

impl ModeSummary {
    fn of(m: &Mode, mac: f64) -> Self {
        Self {
            frequency_rad_s: m.frequency_rad_s,
            damping_ratio: m.damping_ratio,
            whirl: m.whirl,
            log_decrement: m.log_decrement(),
            forward_share: forward_share(&m.shape),
            mac,
        }
    }
}

/// A crossing of a mode with a rotor's 1× excitation line.
#[derive(Clone, Debug, PartialEq)]
pub struct CriticalSpeed {
    /// The exciting rotor's id.
    pub rotor_id: String,
    /// Its speed ratio; the line's slope is its magnitude (negative: the rotor and its
    /// unbalance turn against the reference rotor).
    pub speed_ratio: f64,
    /// Mode number, 1-based: the followed mode's rank in frequency at the first speed.
    pub mode: usize,
    /// Whirl of the mode at the crossing.
    pub whirl: Whirl,
    /// Share of forward whirl in the mode's shape at the crossing ([`forward_share`]).
    pub forward_share: f64,
    /// Reference speed ω at the crossing (rad/s).
    pub speed_rad_s: f64,
    /// Mode frequency at the crossing (rad/s) = |speed_ratio| × speed_rad_s.
    pub frequency_rad_s: f64,
}

impl CriticalSpeed {
    /// Whether the rotor's unbalance excites the mode: a rotating unbalance is a force
    /// turning with its rotor, which does work only on the part of a shape that whirls the
    /// same way (forward, or backward for a counter-rotating rotor). A backward mode of an
    /// isotropic rotor (share 0) is not excited; with anisotropic supports a backward mode
    /// has some forward part and responds in proportion. Counted as excited when the
    /// forward part dominates (share ≥ 0.5).
    pub fn excited_by_unbalance(&self) -> bool {
        if self.speed_ratio < 0.0 {
            // a counter-rotating rotor's unbalance turns backward (against +x → +y)
            self.forward_share <= 0.5
        } else {
            self.forward_share >= 0.5
        }
    }
}

/// A Campbell diagram.
#[derive(Clone, Debug)]
pub struct Campbell {
    pub points: Vec<CampbellPoint>,
    pub critical_speeds: Vec<CriticalSpeed>,
    /// The 1× excitation lines: a rotor id and its signed speed ratio per distinct
    /// spinning speed (the line's slope is the ratio's magnitude).
    pub lines: Vec<(String, f64)>,
}

/// Modal assurance criterion of two complex shapes: `|aᴴb|² / (aᴴa · bᴴb)`, 1 for the same
/// shape (up to a complex factor), 0 for orthogonal ones.
pub fn mac(a: &[Complex<f64>], b: &[Complex<f64>]) -> f64 {
    let ab: Complex<f64> = a.iter().zip(b).map(|(x, y)| x.conj() * y).sum();
    let aa: f64 = a.iter().map(|x| x.norm_sqr()).sum();
    let bb: f64 = b.iter().map(|x| x.norm_sqr()).sum();
    if aa == 0.0 || bb == 0.0 {
        0.0
    } else {
        ab.norm_sqr() / (aa * bb)
    }
}

/// Share of forward whirl in a shape (node-major `[x, y, θx, θy]`): each node's orbit
/// `(x, y) = Re((X, Y) e^{iωt})` is a forward circle of radius `|X + iY|/2` plus a backward
/// one of radius `|X − iY|/2`; the share is `Σ f² / Σ (f² + b²)` over the translations (or
/// the slopes, where those carry more), 1 for a purely forward mode, 0 for a backward one.
pub fn forward_share(shape: &[Complex<f64>]) -> f64 {
    let i = Complex::new(0.0, 1.0);
    let off = whirl_plane(&[shape]);
    let (mut f, mut n) = (0.0, 0.0);
    for node in shape.chunks_exact(4) {
        let (px, py) = (node[off], node[off + 1]);
        let fw = (0.5 * (px + i * py)).norm_sqr();
        f += fw;
        n += fw + (0.5 * (px - i * py)).norm_sqr();
    }
    if n == 0.0 { 0.5 } else { f / n }
}

/// Extra modes solved at each speed beyond those followed, so that a followed mode that
/// moves up past others in frequency is still among the candidates.
const SPARE_MODES: usize = 4;

/// Relative distance of eigenvalues below which modes count as one degenerate cluster
/// (e.g. the forward and backward translation of a disk at a node without tilt, equal at
/// every speed), whose individual shapes are any basis of the cluster's plane.
const DEGENERATE: f64 = 1e-5;

/// Share of `shape` in the span of `basis` (orthonormal): `‖P shape‖² / ‖shape‖²`.
fn share_in(shape: &[Complex<f64>], basis: &[Vec<Complex<f64>>]) -> f64 {
    let nn: f64 = shape.iter().map(|x| x.norm_sqr()).sum();
    if nn == 0.0 {
        return 0.0;
    }
    basis
        .iter()
        .map(|q| {
            q.iter()
                .zip(shape)
                .map(|(a, b)| a.conj() * b)
                .sum::<Complex<f64>>()
                .norm_sqr()
        })
        .sum::<f64>()
        / nn
}

/// Orthonormal basis of the span of `shapes` (Gram–Schmidt).
fn orthonormal(shapes: &[&[Complex<f64>]]) -> Vec<Vec<Complex<f64>>> {
    let mut out: Vec<Vec<Complex<f64>>> = Vec::new();
    for s in shapes {
        let mut v = s.to_vec();
        for q in &out {
            let p: Complex<f64> = q.iter().zip(&v).map(|(a, b)| a.conj() * b).sum();
            v.iter_mut().zip(q).for_each(|(x, y)| *x -= p * y);
        }
        let n = v.iter().map(|x| x.norm_sqr()).sum::<f64>().sqrt();
        if n > 1e-12 {
            v.iter_mut().for_each(|x| *x /= n);
            out.push(v);
        }
    }
    out
}

/// Assigns to each followed shape in `previous` one of `candidates`; returns, per followed
/// mode, the candidate's index and the match (MAC, or the share in a degenerate cluster's
/// span). Candidates with equal eigenvalues ([`DEGENERATE`]) form clusters, matched as a
/// whole by the share of the old shape in their span; pairs of a followed mode and a
/// cluster with room are taken greedily in order of decreasing match, and within a
/// cluster its members go to its followed modes by MAC.
fn follow(previous: &[Vec<Complex<f64>>], candidates: &[Mode]) -> Vec<(usize, f64)> {
    let mut clusters: Vec<Vec<usize>> = Vec::new();
    for (c, m) in candidates.iter().enumerate() {
        match clusters.iter_mut().find(|cl| {
            let e = candidates[cl[0]].eigenvalue;
            (e - m.eigenvalue).norm() <= DEGENERATE * e.norm().max(m.eigenvalue.norm())
        }) {
            Some(cl) => cl.push(c),
            None => clusters.push(vec![c]),
        }
    }
    let spans: Vec<Vec<Vec<Complex<f64>>>> = clusters
        .iter()
        .map(|cl| {
            let shapes: Vec<&[Complex<f64>]> =
                cl.iter().map(|&c| candidates[c].shape.as_slice()).collect();
            orthonormal(&shapes)
        })
        .collect();
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for (t, shape) in previous.iter().enumerate() {
        for (k, span) in spans.iter().enumerate() {
            pairs.push((share_in(shape, span), t, k));
        }
    }
    pairs.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut cluster_of = vec![usize::MAX; previous.len()];
    let mut score = vec![0.0; previous.len()];
    let mut room: Vec<usize> = clusters.iter().map(Vec::len).collect();
    for (v, t, k) in pairs {
        if cluster_of[t] == usize::MAX && room[k] > 0 {
            cluster_of[t] = k;
            score[t] = v;
            room[k] -= 1;
        }
    }
    let mut out = vec![(usize::MAX, 0.0); previous.len()];
    for (k, cl) in clusters.iter().enumerate() {
        let tracks: Vec<usize> = (0..previous.len())
            .filter(|&t| cluster_of[t] == k)
            .collect();
        let mut inner: Vec<(f64, usize, usize)> = Vec::new();
        for &t in &tracks {
            for &c in cl {
                inner.push((mac(&previous[t], &candidates[c].shape), t, c));
            }
        }
        inner.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut taken = vec![false; candidates.len()];
        for (_, t, c) in inner {
            if out[t].0 == usize::MAX && !taken[c] {
                out[t] = (c, score[t]);
                taken[c] = true;
            }
        }
    }
    out
}

/// The mode at `w` that continues `shape` (largest MAC among the candidates).
fn mode_like(
    asm: &Assembly,
    w: f64,
    shape: &[Complex<f64>],
    count: usize,
) -> Result<Option<Mode>, LinearError> {
    let ms = modes(asm, w, count + SPARE_MODES)?;
    Ok(ms
        .into_iter()
        .max_by(|a, b| mac(shape, &a.shape).total_cmp(&mac(shape, &b.shape))))
}

/// Locates the root of `g(ω) = f(ω) − s ω` for the followed mode in a bracket by the
/// Illinois variant of regula falsi (each evaluation is a modal solve, the mode picked by
/// MAC with the shape at the bracket's start), to 1e-10 relative in ω or 40 evaluations;
/// returns the speed and the mode there.
fn refine_crossing(
    asm: &Assembly,
    shape: &[Complex<f64>],
    s: f64,
    (mut a, mut ga): (f64, f64),
    (mut b, mut gb): (f64, f64),
    count: usize,
) -> Result<Option<(f64, Mode)>, LinearError> {
    let eval = |w: f64| -> Result<Option<(f64, Mode)>, LinearError> {
        Ok(mode_like(asm, w, shape, count)?.map(|m| (m.frequency_rad_s - s * w, m)))
    };
    if ga == 0.0 {
        return Ok(eval(a)?.map(|(_, m)| (a, m)));
    }
    let mut side = 0i8;
    let mut best = None;
    for _ in 0..40 {
        let w = (a * gb - b * ga) / (gb - ga);
        let Some((g, m)) = eval(w)? else {
            break;
        };
        best = Some((w, m));
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

/// Campbell diagram of the `count` lowest modes at the first speed, each followed over
/// `speeds` (rad/s, increasing) by its shape: at every speed the modes are matched to the
/// previous speed's by the modal assurance criterion ([`mac`]), so a mode keeps its number
/// when it crosses another in frequency or changes its whirl. Critical speeds are where a
/// followed mode crosses a rotor's 1× line, located by regula falsi on that mode.
pub fn campbell(asm: &Assembly, speeds: &[f64], count: usize) -> Result<Campbell, LinearError> {
    if speeds.len() < 2 || speeds.windows(2).any(|w| w[1] <= w[0]) {
        return Err(LinearError::BadSpeeds(
            "need at least two strictly increasing speeds".into(),
        ));
    }
    let mut points = Vec::with_capacity(speeds.len());
    // shapes of the followed modes at every speed
    let mut shapes: Vec<Vec<Vec<Complex<f64>>>> = Vec::with_capacity(speeds.len());
    for (k, &w) in speeds.iter().enumerate() {
        let (summaries, now) = if k == 0 {
            let ms = modes(asm, w, count)?;
            let sum = ms.iter().map(|m| ModeSummary::of(m, 1.0)).collect();
            (sum, ms.into_iter().map(|m| m.shape).collect::<Vec<_>>())
        } else {
            let previous = &shapes[k - 1];
            let ms = modes(asm, w, previous.len() + SPARE_MODES)?;
            let pick = follow(previous, &ms);
            let mut sum = Vec::new();
            let mut now = Vec::new();
            for &(c, v) in &pick {
                if c == usize::MAX {
                    break;
                }
                sum.push(ModeSummary::of(&ms[c], v));
                now.push(ms[c].shape.clone());
            }
            (sum, now)
        };
        points.push(CampbellPoint {
            speed_rad_s: w,
            modes: summaries,
        });
        shapes.push(now);
    }
    let mut critical_speeds = Vec::new();
    // one 1× line per spinning speed, at the rotor's |ratio| (a counter-rotating rotor's
    // unbalance excites at |s| ω too, turning the other way)
    let mut lines: Vec<(String, f64)> = Vec::new();
    for g in &asm.gyro {
        let signed = g.speed_ratio.value();
        if signed != 0.0 && !lines.iter().any(|(_, v)| *v == signed) {
            lines.push((g.rotor_id.clone(), signed));
        }
    }
    for (rotor_id, signed) in &lines {
        let s = &signed.abs();
        for (k, pair) in points.windows(2).enumerate() {
            let (p0, p1) = (&pair[0], &pair[1]);
            for (i, ((m0, m1), shape)) in p0.modes.iter().zip(&p1.modes).zip(&shapes[k]).enumerate()
            {
                let g0 = m0.frequency_rad_s - s * p0.speed_rad_s;
                let g1 = m1.frequency_rad_s - s * p1.speed_rad_s;
                if g0 == 0.0 || (g0 > 0.0) != (g1 > 0.0) {
                    let Some((w, m)) = refine_crossing(
                        asm,
                        shape,
                        *s,
                        (p0.speed_rad_s, g0),
                        (p1.speed_rad_s, g1),
                        count,
                    )?
                    else {
                        continue;
                    };
                    critical_speeds.push(CriticalSpeed {
                        rotor_id: rotor_id.clone(),
                        speed_ratio: *signed,
                        mode: i + 1,
                        whirl: m.whirl,
                        forward_share: forward_share(&m.shape),
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
        lines,
    })
}

#[cfg(test)]
mod shape_scaling_tests {
    use super::*;

    #[test]
    fn shapes_are_scaled_on_their_largest_translation_not_a_slope() {
        // node 1: small translations, a slope ten times larger in number (rad, not m)
        let shape = vec![
            Complex::new(0.001, 0.0),
            Complex::new(0.0, 0.002),
            Complex::new(0.02, 0.0),
            Complex::new(0.0, 0.0),
            Complex::new(0.0, -0.004),
            Complex::new(0.003, 0.0),
            Complex::new(0.0, 0.0),
            Complex::new(0.01, 0.0),
        ];
        assert_eq!(shape_pivot(&shape), Complex::new(0.0, -0.004));
        // a pure tilt mode: the largest slope
        let tilt = vec![
            Complex::new(0.0, 0.0),
            Complex::new(0.0, 0.0),
            Complex::new(0.3, 0.0),
            Complex::new(0.0, 0.5),
        ];
        assert_eq!(shape_pivot(&tilt), Complex::new(0.0, 0.5));
    }
}

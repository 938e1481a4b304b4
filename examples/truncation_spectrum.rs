//! Where the Eq. 36 residual of the truncated dual-rotor solution sits in frequency.
//!
//! For each truncation order at the given speeds (default 400 and 530 rad/s, where the
//! traced branch has a single solution, so Newton from the static start guess finds the
//! one `tmrotor truncation` reports), the residual at dynamic node 8 (3# bearing, x and y)
//! is sampled on the study's grid (4096 samples over the period 20π/ω) and split by
//! frequency, in multiples of ω/10: components at frequencies of the basis, components
//! below the basis's highest frequency that the basis does not contain (combination
//! tones such as (λ − 1)ω = ω/5 and (λ + 1)ω = 11ω/5), and everything above it.
//!
//! ```sh
//! cargo run --release --example truncation_spectrum [-- 400 530]
//! ```

use rustfft::FftPlanner;
use rustfft::num_complex::Complex64;
use tmrotor::hb::newton::{self, NewtonOptions};
use tmrotor::hb::{HarmonicBalance, HbSolution, time_domain_residual};
use tmrotor::model::Dir;
use tmrotor::sweep::{FloquetSettings, HarmonicSettings, StudySettings, SweepProblem};

const SAMPLES: usize = 4096;

/// One-sided amplitude spectrum of a real series: `amp[k]` of `cos/sin(2π k j / N)`.
fn amplitudes(series: &[f64]) -> Vec<f64> {
    let n = series.len();
    let mut buf: Vec<Complex64> = series
        .iter()
        .map(|v| Complex64::new(*v / n as f64, 0.0))
        .collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buf);
    (0..n / 2)
        .map(|k| {
            if k == 0 {
                buf[0].norm()
            } else {
                2.0 * buf[k].norm()
            }
        })
        .collect()
}

fn main() -> anyhow::Result<()> {
    let speeds: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse::<f64>())
        .collect::<Result<_, _>>()?;
    let speeds = if speeds.is_empty() {
        vec![400.0, 530.0]
    } else {
        speeds
    };
    println!(
        "omega_rad_s,order,rms_n,in_basis_rms_n,missing_below_top_rms_n,above_top_rms_n,top_frequencies"
    );
    for &omega in &speeds {
        for order in 1..=4u32 {
            let settings = StudySettings {
                harmonic: HarmonicSettings {
                    order,
                    ..Default::default()
                },
                floquet: FloquetSettings {
                    stability: false,
                    ..Default::default()
                },
                ..Default::default()
            };
            let p = SweepProblem::new(&settings)?;
            let hb = HarmonicBalance::new(&p.system, &p.basis, None)?;
            let guess = p.system.initial_guess(p.basis.n_coeffs());
            let (a, stats) = newton::solve_fixed(&hb, omega, &guess, &NewtonOptions::default())?;
            let n_mech = a.len() / p.basis.n_coeffs() - tmrotor::system::System::n_therm(&p.system);
            let sol = HbSolution::from_unknowns(omega, &p.basis, n_mech, &a, &stats);
            let r = time_domain_residual(&p.system, &sol, Some(SAMPLES))?;
            let multiples: Vec<usize> = (0..p.basis.n_harmonics())
                .map(|h| p.basis.integer_multiple(h) as usize)
                .collect();
            let top = multiples.iter().copied().max().unwrap_or(0);
            // power per bin summed over x and y
            let mut power = vec![0.0; SAMPLES / 2];
            for dir in [Dir::X, Dir::Y] {
                let dof = p
                    .model
                    .dof(8, dir)
                    .ok_or_else(|| anyhow::anyhow!("the model has no node 8"))?;
                let series = r
                    .mech_series(dof)
                    .ok_or_else(|| anyhow::anyhow!("no residual for DoF {dof}"))?;
                for (k, amp) in amplitudes(series).iter().enumerate() {
                    power[k] += if k == 0 { amp * amp } else { amp * amp / 2.0 };
                }
            }
            let (mut inb, mut below, mut above) = (0.0, 0.0, 0.0);
            for (k, pk) in power.iter().enumerate() {
                if k == 0 || multiples.contains(&k) {
                    inb += pk;
                } else if k < top {
                    below += pk;
                } else {
                    above += pk;
                }
            }
            let mut bins: Vec<(usize, f64)> = power.iter().copied().enumerate().collect();
            bins.sort_by(|x, y| y.1.total_cmp(&x.1));
            let tops: Vec<String> = bins
                .iter()
                .take(5)
                .map(|(k, pk)| format!("{}ω:{:.1}N", *k as f64 / 10.0, pk.sqrt()))
                .collect();
            println!(
                "{omega},{order},{:.3},{:.3},{:.3},{:.3},{}",
                (inb + below + above).sqrt(),
                inb.sqrt(),
                below.sqrt(),
                above.sqrt(),
                tops.join(" ")
            );
        }
    }
    Ok(())
}

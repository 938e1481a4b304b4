//! Helpers shared by the integration tests (`mod common;` in each test file that uses
//! them; each test binary uses a part, hence `dead_code` is allowed).
#![allow(dead_code)]

use std::path::Path;

use clap::Parser;
use tmrotor::cli::replay::{self, Cli};

/// Runs `replay ARGS` in-process: the result, stdout and stderr.
pub fn replay_in_process(args: &[&str]) -> (anyhow::Result<()>, String, String) {
    let cli = Cli::try_parse_from(std::iter::once("replay").chain(args.iter().copied()))
        .expect("arguments parse");
    let (mut out, mut err) = (Vec::new(), Vec::new());
    let res = replay::run(cli, &mut out, &mut err);
    (
        res,
        String::from_utf8_lossy(&out).into_owned(),
        String::from_utf8_lossy(&err).into_owned(),
    )
}

/// Width, height and RGB bytes of a PNG file.
pub fn png_pixels(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    ));
    let mut reader = decoder.read_info().expect("png header");
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("png data");
    (info.width, info.height, buf)
}

/// Whether RGB bytes hold the colour `c` exactly.
pub fn has_colour(px: &[u8], c: plotters::style::RGBColor) -> bool {
    px.chunks(3).any(|p| p == [c.0, c.1, c.2])
}

/// A campaign of three short mechanical runs (order 1, ω 400–402 rad/s, at most 3 points,
/// no stability): seconds in all.
pub const SMALL_CAMPAIGN: &str = r#"
output_dir = "out"
[defaults]
order = 1
omega_start = 400.0
omega_end = 402.0
max_points = 3
stability = false
thermal = false
[[runs]]
name = "a"
[[runs]]
name = "b"
ambient_temp_c = 30.0
[[runs]]
name = "c"
"#;

/// The Python with the official MCAP readers (`TMROTOR_PYTHON`); `None` (the test says it
/// skips that part) when it is not set, except under `CI=true`, where that fails.
pub fn python() -> Option<String> {
    match std::env::var("TMROTOR_PYTHON") {
        Ok(p) if !p.is_empty() => Some(p),
        _ => {
            let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
            assert!(!ci, "CI=true but TMROTOR_PYTHON is not set");
            eprintln!("skipped: TMROTOR_PYTHON is not set");
            None
        }
    }
}

/// A synthetic recording's data with a second branch: the branch on the doubled basis
/// (`continuation::switch::doubled_basis`) leaving the run at its point 10, and four points
/// on it, the synthetic points 8–11 with a half-order harmonic added (index after the
/// run's last point).
pub struct TwoBranches {
    pub data: tmrotor::record::synthetic::SyntheticRun,
    pub doubled: tmrotor::hb::Basis,
    pub branch: tmrotor::record::BranchRecord,
    pub branch_points: Vec<tmrotor::record::PointRecord>,
}

impl TwoBranches {
    pub fn new() -> Self {
        use tmrotor::continuation::switch::{doubled_basis, embed};
        let data = tmrotor::record::synthetic::generate(&Default::default());
        let basis = data.run.basis().expect("basis");
        let doubled = doubled_basis(&basis).expect("doubled");
        let branch = tmrotor::record::BranchRecord {
            branch: 1,
            kind: "period_doubled".into(),
            parent: 0,
            origin_bifurcation: 0,
            origin_omega_rad_s: data.points[10].omega_rad_s,
            harmonics: doubled.harmonics().to_vec(),
        };
        let branch_run = branch.run_of(&data.run);
        let last = data.points.last().expect("points").index;
        let new_harmonic = doubled
            .harmonics()
            .iter()
            .position(|h| !basis.harmonics().contains(h))
            .expect("a new harmonic");
        let nc = doubled.n_coeffs();
        let branch_points = data.points[8..12]
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let mut mech = embed(&p.coeffs_mech, &basis, &doubled);
                for d in 0..data.run.n_mech {
                    mech[d * nc + 1 + new_harmonic] = 1e-6 * (d + 1) as f64;
                }
                let therm = embed(&p.coeffs_therm, &basis, &doubled);
                let mut q = tmrotor::derive::point_from_coefficients(
                    &branch_run,
                    last + 1 + k as u64,
                    p.omega_rad_s,
                    mech,
                    therm,
                    64,
                )
                .expect("branch point");
                q.branch = 1;
                q
            })
            .collect();
        Self {
            data,
            doubled,
            branch,
            branch_points,
        }
    }

    /// Writes the run, the branch and its points to an MCAP file.
    pub fn write(&self, path: &Path) {
        use tmrotor::record::{McapOptions, McapSink, RunStatus, Sink};
        let mut file = McapSink::create(path, McapOptions::default()).expect("create");
        file.begin_run(&self.data.run).expect("begin");
        for p in &self.data.points {
            file.write_point(p).expect("point");
        }
        file.write_branch(&self.branch).expect("branch");
        for p in &self.branch_points {
            file.write_point(p).expect("branch point");
        }
        file.finish(RunStatus::Completed).expect("finish");
    }
}

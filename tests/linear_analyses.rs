//! The linear analyses a rotordynamics user expects, against closed forms: modes followed
//! by shape through a crossing on the Campbell diagram, critical speeds split into forward
//! and backward and marked by whether unbalance excites them; and the commands that write
//! them (`campbell`, `modes`, `unbalance`) as CSV and figures. (Eigenvalues and unbalance
//! responses against ROSS: `tests/ross_linear.rs`.)

use std::f64::consts::PI;

use tmrotor::cli::{Cli, Command, campbell, modes, unbalance};
use tmrotor::linear::{self, Whirl};
use tmrotor::model::{Assembly, Model};

fn example(name: &str) -> String {
    format!("{}/examples/rotors/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn ross_fixture(name: &str) -> String {
    format!("{}/tests/fixtures/ross/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The Jeffcott rotor of `examples/rotors/jeffcott_midspan_disk.toml`: its header's closed
/// forms. Tilt stiffness of the centre couple on a pinned Timoshenko shaft.
fn jeffcott_tilt_stiffness() -> f64 {
    let (e, nu, d, l) = (210e9_f64, 0.3_f64, 0.01_f64, 1.0_f64);
    let i = PI * d.powi(4) / 64.0;
    let a = PI * d * d / 4.0;
    let g = e / (2.0 * (1.0 + nu));
    let kappa = 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu);
    1.0 / (l / (12.0 * e * i) + 1.0 / (kappa * g * a * l))
}

const JD: f64 = 0.05;
const JP: f64 = 0.1;

/// Backward tilt frequency at spin Ω: `J_d ν² + Ω J_p ν − k_θ = 0`.
fn backward_tilt(omega: f64) -> f64 {
    let k = jeffcott_tilt_stiffness();
    (-omega * JP + ((omega * JP).powi(2) + 4.0 * JD * k).sqrt()) / (2.0 * JD)
}

/// The backward tilt mode falls from 157 rad/s through the translation pair (22.24 rad/s,
/// at Ω ≈ 545 rad/s) to 12.3 rad/s at 1000 rad/s. Sorted by frequency it would become
/// "mode 1" there; followed by shape it keeps its number, its whirl and the closed form.
#[test]
fn campbell_follows_the_backward_tilt_through_the_translation_pair() {
    let model = Model::from_file(example("jeffcott_midspan_disk.toml")).expect("model");
    let asm = Assembly::new(&model).expect("assembles");
    let speeds = linear::speed_grid(0.0, 1000.0, 101).expect("grid");
    let c = linear::campbell(&asm, &speeds, 4).expect("campbell");
    // the followed mode that is backward tilt at the first speed above zero
    let tilt = c.points[1]
        .modes
        .iter()
        .position(|m| m.whirl == Whirl::Backward && m.frequency_rad_s > 100.0)
        .expect("a backward tilt mode");
    for p in c.points.iter().skip(1) {
        let m = &p.modes[tilt];
        let want = backward_tilt(p.speed_rad_s);
        assert!(
            (m.frequency_rad_s - want).abs() < 1e-4 * want,
            "at {} rad/s: followed mode at {} rad/s, closed form {want}",
            p.speed_rad_s,
            m.frequency_rad_s
        );
        assert_eq!(m.whirl, Whirl::Backward, "at {} rad/s", p.speed_rad_s);
        assert!(m.mac > 0.99, "at {} rad/s: MAC {}", p.speed_rad_s, m.mac);
    }
    // below the translation pair at the end: frequency order would have renumbered it
    let last = c.points.last().expect("points");
    let lowest = last
        .modes
        .iter()
        .map(|m| m.frequency_rad_s)
        .fold(f64::INFINITY, f64::min);
    assert_eq!(last.modes[tilt].frequency_rad_s, lowest);
    assert!(tilt > 0, "not the lowest at the first speed");
}

/// Critical speeds: the translation pair at √(k/m) once forward (excited by unbalance) and
/// once backward (not), the backward tilt where `ν = Ω`: `Ω = √(k_θ/(J_d + J_p))`, not
/// excited; the forward tilt rises faster than 1× and is never crossed.
#[test]
fn critical_speeds_are_split_by_whirl_and_marked_by_excitation() {
    let model = Model::from_file(example("jeffcott_midspan_disk.toml")).expect("model");
    let asm = Assembly::new(&model).expect("assembles");
    let speeds = linear::speed_grid(0.0, 300.0, 61).expect("grid");
    let c = linear::campbell(&asm, &speeds, 4).expect("campbell");
    assert_eq!(c.critical_speeds.len(), 3, "{:?}", c.critical_speeds);
    let trans: Vec<_> = c
        .critical_speeds
        .iter()
        .filter(|cs| (cs.speed_rad_s - 22.2417).abs() < 0.01)
        .collect();
    assert_eq!(trans.len(), 2);
    let fwd = trans
        .iter()
        .find(|cs| cs.whirl == Whirl::Forward)
        .expect("forward");
    let bwd = trans
        .iter()
        .find(|cs| cs.whirl == Whirl::Backward)
        .expect("backward");
    assert!(fwd.excited_by_unbalance() && fwd.forward_share > 0.999);
    assert!(!bwd.excited_by_unbalance() && bwd.forward_share < 1e-3);
    let tilt_speed = (jeffcott_tilt_stiffness() / (JD + JP)).sqrt();
    let tilt = c
        .critical_speeds
        .iter()
        .find(|cs| (cs.speed_rad_s - tilt_speed).abs() < 1e-4 * tilt_speed)
        .expect("the backward tilt crossing");
    assert_eq!(tilt.whirl, Whirl::Backward);
    assert!(!tilt.excited_by_unbalance());
}

/// The log decrement of a single damped oscillator is `2πζ/√(1−ζ²)`.
#[test]
fn log_decrement_of_a_damped_mode() {
    let lam = num_complex::Complex::new(-0.05 * 100.0, 100.0 * (1.0 - 0.05f64 * 0.05).sqrt());
    let want = 2.0 * PI * 0.05 / (1.0 - 0.05f64 * 0.05).sqrt();
    assert!((linear::log_decrement(lam) - want).abs() < 1e-14);
}

fn parse(args: &[&str]) -> Command {
    use clap::Parser;
    Cli::try_parse_from(args)
        .expect("parses")
        .command
        .expect("a command")
}

#[test]
fn the_commands_write_csv_and_figures() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = |f: &str| dir.path().join(f).display().to_string();
    let model = ross_fixture("cross_coupled.toml");

    let Command::Campbell(a) = parse(&[
        "tmrotor",
        "campbell",
        "--model",
        &model,
        "--speeds",
        "0:1000:41",
        "--count",
        "6",
        "--csv",
        &p("campbell.csv"),
        "--figure",
        &p("campbell"),
        "--format",
        "png",
    ]) else {
        panic!("campbell")
    };
    let mut out = Vec::new();
    campbell::run(&a, &mut out).expect("campbell runs");
    let text = String::from_utf8(out).expect("utf-8");
    assert!(text.contains("excited by unbalance"), "{text}");
    let csv = std::fs::read_to_string(p("campbell.csv")).expect("csv");
    assert!(csv.starts_with("speed_rad_s,mode,frequency_rad_s,frequency_hz,damping_ratio,log_decrement,whirl,forward_share,mac\n"));
    assert_eq!(csv.lines().count(), 1 + 41 * 6);
    assert!(std::fs::metadata(p("campbell.png")).expect("png").len() > 1000);

    let Command::Modes(a) = parse(&[
        "tmrotor",
        "modes",
        "--model",
        &model,
        "--speed",
        "300",
        "--count",
        "4",
        "--shapes",
        &p("shapes.csv"),
        "--figure",
        &p("shapes"),
        "--format",
        "svg",
    ]) else {
        panic!("modes")
    };
    let mut out = Vec::new();
    modes::run(&a, &mut out).expect("modes runs");
    let text = String::from_utf8(out).expect("utf-8");
    assert!(text.contains("log dec"), "{text}");
    let shapes = std::fs::read_to_string(p("shapes.csv")).expect("shapes");
    assert_eq!(shapes.lines().count(), 1 + 4 * 7, "four modes, seven nodes");
    assert!(std::fs::metadata(p("shapes.svg")).expect("svg").len() > 1000);

    let Command::Unbalance(a) = parse(&[
        "tmrotor",
        "unbalance",
        "--model",
        &model,
        "--speeds",
        "100:900:81",
        "--nodes",
        "3,7",
        "--csv",
        &p("unbalance.csv"),
        "--figure",
        &p("unbalance"),
        "--format",
        "png",
    ]) else {
        panic!("unbalance")
    };
    let mut out = Vec::new();
    unbalance::run(&a, &mut out).expect("unbalance runs");
    let text = String::from_utf8(out).expect("utf-8");
    assert!(text.contains("peak ω"), "{text}");
    let csv = std::fs::read_to_string(p("unbalance.csv")).expect("csv");
    assert_eq!(csv.lines().count(), 1 + 81 * 7);
    // the response at 300 rad/s is the library's, which tests/ross_linear.rs checks
    let row = csv
        .lines()
        .find(|l| l.starts_with("300,rotor,300,3,"))
        .expect("a row at 300 rad/s, node 3");
    let amp: f64 = row
        .split(',')
        .nth(4)
        .expect("x amplitude")
        .parse()
        .expect("number");
    let asm = Assembly::new(&Model::from_file(&model).expect("model")).expect("asm");
    let r = linear::unbalance_response(&asm, &[300.0]).expect("response");
    assert!((amp - r[0].node(2).x.norm()).abs() < 1e-6 * amp);
    assert!(std::fs::metadata(p("unbalance.png")).expect("png").len() > 1000);

    // a node that does not exist is named
    let Command::Unbalance(a) = parse(&[
        "tmrotor",
        "unbalance",
        "--model",
        &model,
        "--speeds",
        "100:900:3",
        "--nodes",
        "42",
    ]) else {
        panic!("unbalance")
    };
    let err = unbalance::run(&a, &mut Vec::new()).expect_err("refused");
    assert!(format!("{err:#}").contains("node 42"), "{err:#}");
}

fn jeffcott_with_ratio(ratio: &str) -> Assembly {
    let text = std::fs::read_to_string(example("jeffcott_midspan_disk.toml")).expect("file");
    let from = "speed_ratio = \"1\"\n";
    assert!(text.contains(from));
    let model = Model::from_str(
        &text.replacen(from, &format!("speed_ratio = {ratio}\n"), 1),
        "j",
    )
    .expect("model");
    Assembly::new(&model).expect("assembles")
}

/// A disk turning against the reference (`speed_ratio = -1`): the gyroscopic split is the
/// same closed form, with the whirl senses exchanged (the mode that whirls with the disk's
/// spin, backward relative to +x → +y, stiffens); the 1× line of its unbalance crosses the
/// mode that whirls against the spin at `Ω = √(k_θ/(J_d + J_p))`, which that unbalance
/// does not excite; of the translation pair, the backward one (with the spin) is excited.
#[test]
fn counter_rotating_disk_mirrors_the_gyroscopic_split() {
    let asm = jeffcott_with_ratio("\"-1\"");
    let omega = 300.0;
    let ms = linear::modes(&asm, omega, 4).expect("modes");
    let k = jeffcott_tilt_stiffness();
    let stiff = (omega * JP + ((omega * JP).powi(2) + 4.0 * JD * k).sqrt()) / (2.0 * JD);
    let soft = backward_tilt(omega);
    let find = |f: f64| {
        ms.iter()
            .find(|m| (m.frequency_rad_s - f).abs() < 1e-4 * f)
            .unwrap_or_else(|| panic!("no mode at {f}: {ms:?}"))
    };
    assert_eq!(find(stiff).whirl, Whirl::Backward, "with the disk's spin");
    assert_eq!(find(soft).whirl, Whirl::Forward, "against the disk's spin");

    let speeds = linear::speed_grid(0.0, 300.0, 61).expect("grid");
    let c = linear::campbell(&asm, &speeds, 4).expect("campbell");
    let tilt_speed = (k / (JD + JP)).sqrt();
    let tilt = c
        .critical_speeds
        .iter()
        .find(|cs| (cs.speed_rad_s - tilt_speed).abs() < 1e-4 * tilt_speed)
        .expect("the crossing of the soft tilt mode");
    assert_eq!(tilt.speed_ratio, -1.0);
    assert!((tilt.frequency_rad_s - tilt.speed_rad_s).abs() < 1e-12 * tilt_speed);
    assert_eq!(tilt.whirl, Whirl::Forward);
    assert!(!tilt.excited_by_unbalance());
    let excited: Vec<Whirl> = c
        .critical_speeds
        .iter()
        .filter(|cs| (cs.speed_rad_s - 22.2417).abs() < 0.01 && cs.excited_by_unbalance())
        .map(|cs| cs.whirl)
        .collect();
    assert_eq!(excited, vec![Whirl::Backward]);
}

/// A part that does not spin (`speed_ratio = 0`): no gyroscopic split, no 1× line.
#[test]
fn a_part_that_does_not_spin() {
    let asm = jeffcott_with_ratio("0");
    let at_rest = linear::modes(&asm, 0.0, 4).expect("modes");
    let fast = linear::modes(&asm, 1000.0, 4).expect("modes");
    for (a, b) in at_rest.iter().zip(&fast) {
        assert!((a.frequency_rad_s - b.frequency_rad_s).abs() < 1e-6 * a.frequency_rad_s);
    }
    let speeds = linear::speed_grid(0.0, 300.0, 7).expect("grid");
    let c = linear::campbell(&asm, &speeds, 4).expect("campbell");
    assert!(c.critical_speeds.is_empty());
}

/// The linear analyses include the `[[nonlinear]]` elements linearised about the
/// undeflected position: the Jeffcott rotor on polynomial supports `[k1, 0, k3]` has the
/// modes of the same rotor on linear supports `k1` (the cubic term's tangent is zero
/// there), and a rub with its gap open adds nothing.
#[test]
fn nonlinear_elements_enter_the_linear_analyses_by_their_tangent() {
    let text = std::fs::read_to_string(example("jeffcott_midspan_disk.toml")).expect("example");
    let cut = text.find("[[supports]]").expect("the example's supports");
    let head = &text[..cut];
    let polynomial = format!(
        "{head}\n[[nonlinear]]\nid = \"left\"\nkind = \"polynomial\"\nnode = 1\n\
         coefficients = [1e12, 0.0, 1e15]\n\n[[nonlinear]]\nid = \"right\"\n\
         kind = \"polynomial\"\nnode = 5\ncoefficients = [1e12, 0.0, 1e15]\n\n\
         [[nonlinear]]\nid = \"stator\"\nkind = \"rub\"\nnode = 3\ngap_m = 5e-4\n\
         stiffness_n_m = 1e6\n"
    );
    let linear = Model::from_file(example("jeffcott_midspan_disk.toml")).expect("model");
    let nonlinear = Model::from_str(&polynomial, "polynomial supports").expect("model");
    let a = linear::modes(&Assembly::new(&linear).expect("assembles"), 300.0, 4).expect("modes");
    let b = linear::modes(&Assembly::new(&nonlinear).expect("assembles"), 300.0, 4).expect("modes");
    for (ma, mb) in a.iter().zip(&b) {
        assert!(
            (ma.frequency_rad_s - mb.frequency_rad_s).abs() <= 1e-9 * ma.frequency_rad_s,
            "{} against {}",
            ma.frequency_rad_s,
            mb.frequency_rad_s
        );
    }
}

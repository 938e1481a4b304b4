//! Inputs a hostile or unlucky user gives: impossible values in a model file refused with
//! the field (the same bound as the flags), a conduction chain naming no rotor, a rotor held
//! by nothing, inputs that are devices, FIFOs or too large, counts of zero and huge grids.

use std::path::Path;
use std::process::{Command, Output};

fn tmrotor(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tmrotor"))
        .args(args)
        .output()
        .expect("runs")
}

fn refused(o: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "accepted: {err}");
    assert_ne!(o.status.code(), Some(101), "panicked: {err}");
    for n in needles {
        assert!(err.contains(n), "{n:?} not in {err}");
    }
}

fn builtin(dir: &Path) -> (std::path::PathBuf, String) {
    let text = String::from_utf8(tmrotor(&["model", "show"]).stdout).expect("utf-8");
    let path = dir.join("m.toml");
    std::fs::write(&path, &text).expect("write");
    (path, text)
}

#[test]
fn impossible_values_in_a_model_file_are_refused_like_the_flags() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (model, _) = builtin(dir.path());
    let m = model.to_str().expect("path");
    for (set, field, why) in [
        (
            "thermal.cooling_temp_c=-500.0",
            "thermal.cooling_temp_c",
            "must lie in (−273.15, 1000)",
        ),
        (
            "thermal.ambient_temp_c=-300.0",
            "thermal.ambient_temp_c",
            "must lie in (−273.15, 1000)",
        ),
        (
            "thermal.flow_l_min=0.0",
            "thermal.flow_l_min",
            "must lie in (0, 1000]",
        ),
        (
            "thermal.air.rotor_convection_factor=5.0",
            "thermal.air.rotor_convection_factor",
            "must lie in [0, 1]",
        ),
    ] {
        refused(
            &tmrotor(&["model", "check", m, "--set", set]),
            &[m, field, why],
        );
    }
    // the flags' bounds are the same
    refused(
        &tmrotor(&["sweep", "--cooling-temp", "-300", "-o", "/tmp/never.mcap"]),
        &["cooling_temp_c"],
    );
}

#[test]
fn a_chain_naming_no_rotor_and_a_rotor_held_by_nothing_are_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (_, text) = builtin(dir.path());
    let bad_chain = dir.path().join("chain.toml");
    std::fs::write(
        &bad_chain,
        text.replacen("chain = \"LP\"", "chain = \"XX\"", 1),
    )
    .expect("write");
    let c = bad_chain.to_str().expect("path");
    refused(
        &tmrotor(&["model", "check", c]),
        &[c, "thermal.shafts[", "chain", "\"XX\" names no rotor"],
    );
    // without gravity and without bearings: the rotors float
    let mut floating = String::new();
    let mut skip = false;
    for line in text.lines() {
        if line.starts_with('[') {
            skip = line.starts_with("[[bearings]]") || line.starts_with("[[thermal.bearings]]");
        }
        if !skip {
            floating.push_str(line);
            floating.push('\n');
        }
    }
    let floating = floating.replace("[gravity]\nenabled = true", "[gravity]\nenabled = false");
    let f = dir.path().join("floating.toml");
    std::fs::write(&f, floating).expect("write");
    let fs = f.to_str().expect("path");
    refused(&tmrotor(&["model", "check", fs]), &[fs, "held by nothing"]);
}

#[test]
fn a_generated_network_too_fine_to_compute_is_refused_with_its_size() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let f = root.join("examples/rotors/dual_rotor_generated.toml");
    let f = f.to_str().expect("path");
    let start = std::time::Instant::now();
    refused(
        &tmrotor(&[
            "model",
            "check",
            f,
            "--set",
            "thermal.segment_length_m=1e-7",
        ]),
        &[
            "thermal.segment_length_m",
            "shaft segment nodes",
            "above the limit of 600",
        ],
    );
    assert!(start.elapsed().as_secs() < 5, "{:?}", start.elapsed());
    // just under the segment limit, the whole network (segments, disks, bearings) is over
    // its own: 1 899 segment nodes took 6.7 GB without finishing a point
    for (length, needles) in [
        (
            "0.0017",
            ["thermal.segment_length_m", "above the limit of 600"],
        ),
        ("0.0055", ["thermal.n_nodes", "above the limit of 600"]),
    ] {
        let set = format!("thermal.segment_length_m={length}");
        refused(&tmrotor(&["model", "check", f, "--set", &set]), &needles);
    }
}

/// The thermal network's bearings are the mechanical ones: a different element count or
/// diameter is a second bearing modelled as one; a pitch circle outside the raceways is no
/// bearing at all.
#[test]
fn a_thermal_bearing_that_is_not_its_mechanical_bearing_is_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (path, _) = builtin(dir.path());
    let f = path.to_str().expect("path");
    for (set, needles) in [
        (
            "thermal.bearings[1#].n_elements=23",
            vec!["thermal.bearings[0].n_elements", "element_count = 22"],
        ),
        (
            "thermal.bearings[1#].element_diameter_m=0.03",
            vec!["thermal.bearings[0].element_diameter_m", "0.01905"],
        ),
        (
            "thermal.bearings[1#].pitch_diameter_m=0.3",
            vec!["thermal.bearings[0].pitch_diameter_m", "outer raceway"],
        ),
    ] {
        refused(&tmrotor(&["model", "check", f, "--set", set]), &needles);
    }
}

/// Negative values written without `=` are values of their flag, refused by name (not
/// clap's "unexpected argument"); settings refused before anything is written.
#[test]
fn negative_values_and_bad_settings_are_refused_by_flag_before_writing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("o.mcap");
    let o = out.to_str().expect("path");
    for (args, flag) in [
        (vec!["sweep", "--flow", "-2"], "--flow"),
        (vec!["sweep", "--omega", "-300:700"], "--omega"),
        (vec!["sweep", "--order", "-1"], "--order"),
        (vec!["sweep", "--ds-max", "-0.1"], "--ds-max"),
        (vec!["transient", "--ramp", "-100:300"], "--ramp"),
        (
            vec!["transient", "--speed", "300", "--rtol", "-1"],
            "--rtol",
        ),
        (
            vec!["transient", "--speed", "300", "--alpha", "-0.5"],
            "--alpha",
        ),
    ] {
        let mut a = args.clone();
        a.extend(["-o", o]);
        refused(&tmrotor(&a), &[flag]);
        assert!(!out.exists(), "{args:?} wrote {o}");
    }
    // a campaign's dry run refuses the output directory a real run would
    let campaign = dir.path().join("c.toml");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/paper_campaign.toml"),
    )
    .expect("campaign");
    let text: String = text
        .lines()
        .map(|l| {
            if l.starts_with("output_dir") {
                "output_dir = \"/dev/null\"".to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(&campaign, text).expect("write");
    let c = campaign.to_str().expect("path");
    refused(
        &tmrotor(&["campaign", c, "--dry-run"]),
        &["output_dir", "/dev/null", "not a directory"],
    );
    // replay's audit with more intervals than a study allows names its flag, not the
    // recording's model
    let rec = dir.path().join("r.mcap");
    let r = rec.to_str().expect("path");
    let made = tmrotor(&["sweep", "--omega", "300:305", "--no-verify", "-q", "-o", r]);
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let o = Command::new(env!("CARGO_BIN_EXE_replay"))
        .args(["stability", r, "--sip-intervals", "1000000000"])
        .output()
        .expect("runs");
    refused(&o, &["--sip-intervals", "at most 200000"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("embedded"));
}

#[test]
fn devices_fifos_and_huge_files_are_refused_before_reading() {
    let dir = tempfile::tempdir().expect("tempdir");
    refused(
        &tmrotor(&["model", "check", "/dev/zero"]),
        &["/dev/zero", "not a regular file"],
    );
    let big = dir.path().join("big.toml");
    let f = std::fs::File::create(&big).expect("create");
    f.set_len(20 << 20).expect("grow");
    let b = big.to_str().expect("path");
    refused(&tmrotor(&["model", "check", b]), &[b, "above the limit"]);
    refused(
        &tmrotor(&["sweep", "--study", "/dev/zero", "-o", "/tmp/never.mcap"]),
        &["/dev/zero", "not a regular file"],
    );
}

#[test]
fn counts_of_zero_and_huge_grids_are_refused() {
    refused(
        &tmrotor(&["modes", "--count", "0"]),
        &["--count", "at least 1"],
    );
    refused(
        &tmrotor(&["campbell", "--speeds", "0:1000:10", "--count", "0"]),
        &["--count", "at least 1"],
    );
    refused(
        &tmrotor(&["campbell", "--speeds", "0:1000:3000000"]),
        &["--speeds", "at most 100000"],
    );
    refused(
        &tmrotor(&["unbalance", "--speeds", "100:1000:100000000"]),
        &["--speeds", "at most 100000"],
    );
    // a negative value reaches the value check instead of clap's "unexpected argument"
    refused(
        &tmrotor(&["modes", "--speed", "-100"]),
        &["--speed", "-100"],
    );
}

#[test]
fn linear_analyses_take_set_and_truncation_names_its_node_flags() {
    let o = tmrotor(&[
        "modes",
        "--speed",
        "500",
        "--count",
        "2",
        "--set",
        "bearings[0].initial_clearance_m=1e-5",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let f = root.join("examples/rotors/jeffcott_midspan_disk.toml");
    // a node the model does not have: the flag, the node and the model's nodes named
    // (without --nodes the model's own disks and bearings are the default)
    refused(
        &tmrotor(&[
            "truncation",
            "--model",
            f.to_str().expect("path"),
            "--nodes",
            "8",
        ]),
        &["--nodes", "dynamic node 8", "its nodes: 1–5"],
    );
    // the tour's study file ships
    assert!(root.join("examples/study.toml").is_file());
}

/// A fixed-seed linear congruential generator: `next(n)` is in `0..n`.
fn lcg(mut seed: u64) -> impl FnMut(usize) -> usize {
    move |n| {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((seed >> 33) as usize) % n.max(1)
    }
}

/// Runs `tmrotor args` for mutation `case`: neither a panic, nor a signal, nor more than
/// `limit_s` seconds. Its output and stderr.
fn run_case(case: usize, args: &[&str], limit_s: f64) -> (Output, String) {
    let started = std::time::Instant::now();
    let o = tmrotor(args);
    let secs = started.elapsed().as_secs_f64();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_ne!(o.status.code(), Some(101), "case {case} panicked: {err}");
    assert!(
        o.status.code().is_some(),
        "case {case} killed by a signal: {err}"
    );
    assert!(secs < limit_s, "case {case} took {secs} s");
    (o, err)
}

/// A fixed-seed corpus of mutated model files (the built-in one with lines deleted,
/// duplicated or cut, numbers replaced by hostile values, bytes flipped): `model check`
/// never panics, never hangs, and a refusal names the file and a line or a field.
#[test]
fn a_corpus_of_mutated_model_files_is_checked_without_a_panic() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (_, text) = builtin(dir.path());
    let lines: Vec<&str> = text.lines().collect();
    let mut next = lcg(0x5EED_CAFE_F00D_D00D);
    let hostile = [
        "0",
        "-1",
        "1e300",
        "-1e300",
        "nan",
        "inf",
        "\"x\"",
        "[]",
        "{}",
        "1e-300",
        "99999999999",
        "-0.0",
        "true",
    ];
    let (mut accepted, mut refused_n) = (0, 0);
    for case in 0..240 {
        let mut ls: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
        let what = case % 6;
        let i = next(ls.len());
        match what {
            0 => {
                ls.remove(i);
            }
            1 => {
                let l = ls[i].clone();
                ls.insert(i, l);
            }
            2 | 3 => {
                // a value replaced by a hostile one, on a `key = number` line
                let candidates: Vec<usize> = (0..ls.len())
                    .filter(|&k| {
                        let l = ls[k].trim_start();
                        !l.starts_with('#')
                            && l.split_once('=').is_some_and(|(_, v)| {
                                v.trim()
                                    .starts_with(|c: char| c.is_ascii_digit() || c == '-')
                            })
                    })
                    .collect();
                let k = candidates[next(candidates.len())];
                let key = ls[k]
                    .split_once('=')
                    .map(|(a, _)| a.to_string())
                    .unwrap_or_default();
                ls[k] = format!("{key}= {}", hostile[next(hostile.len())]);
            }
            4 => {
                let l = &ls[i];
                let cut = next(l.len() + 1);
                let cut = (0..=cut)
                    .rev()
                    .find(|&c| l.is_char_boundary(c))
                    .unwrap_or(0);
                ls[i] = l[..cut].to_string();
            }
            _ => {
                ls.truncate(i);
            }
        }
        let mut bytes = ls.join("\n").into_bytes();
        if case % 17 == 0 && !bytes.is_empty() {
            let b = next(bytes.len());
            bytes[b] ^= 0x80; // not UTF-8 any more, or another character
        }
        let path = dir.path().join(format!("case{case}.toml"));
        std::fs::write(&path, &bytes).expect("write");
        let p = path.to_str().expect("path");
        let (o, err) = run_case(case, &["model", "check", p], 20.0);
        if o.status.success() {
            accepted += 1;
        } else {
            refused_n += 1;
            assert!(
                err.contains(&format!("case{case}.toml")),
                "case {case}: the error does not name the file: {err}"
            );
            // a line number or a field path after the file name
            let after = err.split(&format!("case{case}.toml")).nth(1).unwrap_or("");
            assert!(
                after.starts_with(':') || after.contains('.') || after.contains('['),
                "case {case}: no line or field named: {err}"
            );
        }
    }
    println!("{accepted} accepted, {refused_n} refused");
    assert!(refused_n > 60, "only {refused_n} of 240 mutations refused");
}

/// The same for campaign files (the shipped paper campaign, mutated), checked with
/// `campaign --dry-run`: never a panic or a hang, and a refusal names the file.
#[test]
fn a_corpus_of_mutated_campaign_files_is_checked_without_a_panic() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("examples/paper_campaign.toml")).expect("read");
    let lines: Vec<&str> = text.lines().collect();
    let mut next = lcg(0xC0FF_EE00_1234_5678);
    let hostile = [
        "0",
        "-1",
        "1e300",
        "nan",
        "\"\"",
        "[]",
        "\"/dev/null\"",
        "-5",
        "1e-300",
    ];
    let mut refused_n = 0;
    for case in 0..80 {
        let mut ls: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
        let i = next(ls.len());
        match case % 4 {
            0 => {
                ls.remove(i);
            }
            1 => {
                let l = ls[i].clone();
                ls.insert(i, l);
            }
            2 => {
                let candidates: Vec<usize> = (0..ls.len())
                    .filter(|&k| {
                        let l = ls[k].trim_start();
                        !l.starts_with('#') && l.contains('=')
                    })
                    .collect();
                let k = candidates[next(candidates.len())];
                let key = ls[k]
                    .split_once('=')
                    .map(|(a, _)| a.to_string())
                    .unwrap_or_default();
                ls[k] = format!("{key}= {}", hostile[next(hostile.len())]);
            }
            _ => {
                ls.truncate(i);
            }
        }
        let path = dir.path().join(format!("camp{case}.toml"));
        std::fs::write(&path, ls.join("\n")).expect("write");
        let p = path.to_str().expect("path");
        let (o, err) = run_case(case, &["campaign", p, "--dry-run"], 30.0);
        if !o.status.success() {
            refused_n += 1;
            assert!(
                err.contains(&format!("camp{case}")),
                "case {case}: the error does not name the file: {err}"
            );
        }
    }
    println!("{refused_n} of 80 refused");
    assert!(refused_n > 10, "only {refused_n} of 80 mutations refused");
}

/// The linear analyses say how they take the nonlinear elements and blame the right thing, and their CSVs
/// carry numbers at full precision (the shortest form that reads back exactly).
#[test]
fn linear_analyses_name_what_they_leave_out_and_write_full_precision() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let rub = root.join("examples/rotors/jeffcott_rub.toml");
    let rub = rub.to_str().expect("path");
    let o = tmrotor(&[
        "modes", "--model", rub, "--speed", "100", "--count", "2", "--csv",
    ]);
    assert!(o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("1 [[nonlinear]] element")
            && err.contains("linearised about the undeflected position"),
        "{err}"
    );
    let csv = String::from_utf8_lossy(&o.stdout);
    let row = csv.lines().nth(1).expect("a mode");
    let freq = row.split(',').nth(1).expect("frequency");
    // more than six decimals, and exactly what the number prints as
    let v: f64 = freq.parse().expect("number");
    assert_eq!(format!("{v}"), freq);
    assert!(
        freq.split('.').nth(1).is_some_and(|d| d.len() > 6),
        "{freq}"
    );
    let contact = root.join("examples/rotors/two_mass_contact.toml");
    let o = tmrotor(&[
        "unbalance",
        "--model",
        contact.to_str().expect("path"),
        "--speeds",
        "1:2:3",
    ]);
    refused(&o, &["no unbalance", "eccentricity_m"]);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("speed grid"));
}

/// A fixed-seed corpus of hostile flag values: one flag of a short sweep (or of `campbell`,
/// `unbalance`, `modes`) given a hostile value. No panic, no hang; a refusal names the
/// flag; an accepted value runs to the end.
#[test]
fn a_corpus_of_hostile_flag_values_is_refused_by_name_or_run() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("f.mcap");
    let out = out.to_str().expect("utf-8 path");
    let hostile = [
        "0",
        "-1",
        "1e300",
        "-1e300",
        "nan",
        "inf",
        "-inf",
        "x",
        "",
        "1e-300",
        "99999999999999999999",
        "1e309",
        "0x10",
        "1:2:3",
        ":",
        "400:",
        "5:4",
        "\u{1F642}",
        "-0",
        "2,0",
    ];
    // (command, flag, the rest of a short run)
    let sweep: &[&str] = &[
        "--order",
        "1",
        "--omega",
        "400:401",
        "--max-points",
        "3",
        "--no-verify",
        "-q",
    ];
    let flags: &[(&str, &str)] = &[
        ("sweep", "--flow"),
        ("sweep", "--cooling-temp"),
        ("sweep", "--ambient-temp"),
        ("sweep", "--order"),
        ("sweep", "--omega"),
        ("sweep", "--ds-max"),
        ("sweep", "--max-points"),
        ("sweep", "--sip-intervals"),
        ("sweep", "--reduction-cutoff"),
        ("sweep", "--stability-method"),
        ("sweep", "--interval-map"),
        ("sweep", "--verify-orders"),
        ("campbell", "--speeds"),
        ("campbell", "--count"),
        ("unbalance", "--speeds"),
        ("modes", "--count"),
    ];
    let mut next = lcg(0xF1A6_5EED_0BAD_CAFE);
    let (mut accepted, mut refused_n) = (0, 0);
    for case in 0..160 {
        let (command, flag) = flags[next(flags.len())];
        let value = hostile[next(hostile.len())];
        // `--flag=value`, so that values starting with '-' are values
        let given = format!("{flag}={value}");
        let mut args: Vec<&str> = vec![command, &given];
        match command {
            "sweep" => {
                // the mutated flag replaces its default in the short run
                let mut rest = sweep.iter();
                while let Some(a) = rest.next() {
                    if *a == flag {
                        rest.next();
                        continue;
                    }
                    args.push(a);
                }
                if flag == "--verify-orders" {
                    // with the check on, over a window without bifurcations
                    args.retain(|a| *a != "--no-verify");
                }
                args.extend(["-o", out]);
            }
            "campbell" if flag == "--count" => args.extend(["--speeds", "0:1000:3"]),
            _ => {}
        }
        let (o, err) = run_case(case, &args, 60.0);
        if o.status.success() {
            accepted += 1;
            continue;
        }
        refused_n += 1;
        assert!(
            err.contains(flag) || err.contains(&flag[2..]),
            "case {case}: `tmrotor {}` refused without naming {flag}: {err}",
            args.join(" ")
        );
    }
    eprintln!("{accepted} hostile flag values accepted, {refused_n} refused by name");
    assert!(
        refused_n > accepted,
        "{refused_n} refused, {accepted} accepted"
    );
}

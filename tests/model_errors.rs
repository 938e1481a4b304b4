//! Broken model files are rejected with the file, the field path and the reason.

use tmrotor::model::{BUILTIN_TOML, InvalidKind, Model, ModelError};

const FILE: &str = "broken.toml";

/// The built-in file with one edit; the edit must apply.
fn edited(from: &str, to: &str) -> String {
    assert!(
        BUILTIN_TOML.contains(from),
        "fixture edit {from:?} not found"
    );
    BUILTIN_TOML.replacen(from, to, 1)
}

fn reject(text: &str) -> ModelError {
    match Model::from_str(text, FILE) {
        Ok(_) => panic!("model was accepted"),
        Err(e) => e,
    }
}

fn check(text: &str, path: &str, kind: impl Fn(&InvalidKind) -> bool) -> ModelError {
    let e = reject(text);
    assert_eq!(e.path(), Some(path), "{e}");
    assert!(kind(e.kind().expect("an invalid-file error")), "{e}");
    let msg = e.to_string();
    assert!(msg.starts_with(FILE), "{msg}");
    assert!(msg.contains(path), "{msg}");
    e
}

#[test]
fn builtin_is_valid_and_keeps_its_thermal_table() {
    let m = Model::from_str(BUILTIN_TOML, FILE).expect("valid");
    let t = m
        .thermal()
        .expect("the built-in model carries the thermal network");
    assert_eq!(t.get("n_nodes").and_then(|v| v.as_integer()), Some(66));
}

#[test]
fn unknown_node_on_a_disk() {
    check(
        &edited(
            "node = 3\nmass_kg = 101.4624",
            "node = 99\nmass_kg = 101.4624",
        ),
        "disks[0].node",
        |k| *k == InvalidKind::UnknownNode(99),
    );
}

#[test]
fn unknown_node_on_a_shaft_element() {
    check(
        &edited("nodes = [8, 9]", "nodes = [8, 90]"),
        "shafts[7].nodes[1]",
        |k| *k == InvalidKind::UnknownNode(90),
    );
}

#[test]
fn inner_diameter_not_below_outer() {
    check(
        &edited(
            "nodes = [2, 3]\ninner_diameter_m = 112e-3",
            "nodes = [2, 3]\ninner_diameter_m = 120e-3",
        ),
        "shafts[1].inner_diameter_m",
        |k| matches!(k, InvalidKind::DiameterOrder { .. }),
    );
}

#[test]
fn zero_length_and_negative_mass() {
    check(
        &edited(
            "outer_diameter_m = 140e-3\nlength_m = 12e-3",
            "outer_diameter_m = 140e-3\nlength_m = 0.0",
        ),
        "shafts[0].length_m",
        |k| *k == InvalidKind::NotPositive(0.0),
    );
    check(
        &edited("mass_kg = 73.115", "mass_kg = -73.115"),
        "disks[1].mass_kg",
        |k| *k == InvalidKind::NotPositive(-73.115),
    );
}

#[test]
fn bearing_on_missing_node() {
    check(
        &edited("inner_node = 12", "inner_node = 40"),
        "bearings[1].inner_node",
        |k| *k == InvalidKind::UnknownNode(40),
    );
    check(
        &edited("outer_node = 18", "outer_node = 19"),
        "bearings[2].outer_node",
        |k| *k == InvalidKind::UnknownNode(19),
    );
}

#[test]
fn duplicate_ids() {
    check(
        &edited("id = \"LPT\"", "id = \"LPC\""),
        "disks[1].id",
        |k| matches!(k, InvalidKind::DuplicateId(s) if s.contains("LPC")),
    );
    check(
        &edited("nodes = [12, 13,", "nodes = [11, 12, 13,"),
        "rotors[1].nodes[0]",
        |k| matches!(k, InvalidKind::DuplicateId(s) if s.contains("11")),
    );
    check(
        &edited("id = \"2#\"", "id = \"1#\""),
        "bearings[1].id",
        |k| matches!(k, InvalidKind::DuplicateId(_)),
    );
}

#[test]
fn unknown_key_with_line() {
    let text = edited("id = \"HPT\"\n", "id = \"HPT\"\ncolour = \"red\"\n");
    let line = text
        .lines()
        .position(|l| l.starts_with("colour"))
        .expect("inserted")
        + 1;
    let e = check(
        &text,
        "disks[3].colour",
        |k| matches!(k, InvalidKind::UnknownKey(s) if s.contains("colour")),
    );
    match e {
        ModelError::Invalid { line: l, .. } => assert_eq!(l, Some(line)),
        other => panic!("{other}"),
    }
    // Unknown top-level table.
    check(
        &format!("{BUILTIN_TOML}\n[solver]\nx = 1\n"),
        "solver",
        |k| matches!(k, InvalidKind::UnknownKey(s) if s.contains("solver")),
    );
}

#[test]
fn wrong_types_and_units() {
    check(
        &edited("mass_kg = 94.2194", "mass_kg = \"94.2194 kg\""),
        "disks[2].mass_kg",
        |k| matches!(k, InvalidKind::WrongType(_)),
    );
    check(
        &edited("element_count = 22", "element_count = 22.5"),
        "bearings[0].element_count",
        |k| matches!(k, InvalidKind::WrongType(_)),
    );
    check(
        &edited(
            "kind = \"ball\"\ninner_node = 1\n",
            "kind = \"needle\"\ninner_node = 1\n",
        ),
        "bearings[0].kind",
        |k| matches!(k, InvalidKind::WrongType(_)),
    );
    check(
        &edited("nodes = [1, 2]\n", "nodes = [1, 2, 3]\n"),
        "shafts[0].nodes",
        |k| matches!(k, InvalidKind::WrongType(_)),
    );
}

#[test]
fn irrational_speed_ratio() {
    for bad in [
        "1.2345678",
        "\"sqrt(2)\"",
        "3.14159265",
        "\"7/0\"",
        "-1.2345678",
    ] {
        check(
            &edited("speed_ratio = \"6/5\"", &format!("speed_ratio = {bad}")),
            "rotors[1].speed_ratio",
            |k| matches!(k, InvalidKind::IrrationalRatio(_)),
        );
    }
    for good in [
        "1.2",
        "\"1.2\"",
        "\"12/10\"",
        "1.25",
        "-1.2",
        "\"-6/5\"",
        "0",
        "\"0\"",
    ] {
        let m = Model::from_str(
            &edited("speed_ratio = \"6/5\"", &format!("speed_ratio = {good}")),
            FILE,
        )
        .expect("clean rational");
        let r = m.speed_ratio(1);
        let want = match good {
            "1.25" => 1.25,
            "-1.2" | "\"-6/5\"" => -1.2,
            "0" | "\"0\"" => 0.0,
            _ => 1.2,
        };
        assert!((r.value() - want).abs() < 1e-15, "{good}: {r}");
    }
}

#[test]
fn missing_key_unknown_material_and_syntax() {
    check(
        &edited("hertz_stiffness = 1.45e9\n", ""),
        "bearings[0]",
        |k| matches!(k, InvalidKind::MissingKey(s) if s.contains("hertz_stiffness")),
    );
    check(
        &edited("material = \"bearing\"", "material = \"brass\""),
        "bearings[0].material",
        |k| *k == InvalidKind::UnknownMaterial("brass".into()),
    );
    let e = reject(&edited("[[disks]]\nid = \"LPC\"", "[[disks]\nid = \"LPC\""));
    assert!(matches!(e.kind(), Some(InvalidKind::Syntax(_))), "{e}");
}

#[test]
fn missing_top_level_key() {
    check(
        &edited("name = \"dual_rotor\"\n", ""),
        "(top level)",
        |k| matches!(k, InvalidKind::MissingKey(s) if s.contains("name")),
    );
}

#[test]
fn bearing_geometry_and_roller_data() {
    check(
        &edited(
            "inner_race_diameter_m = 150.95e-3",
            "inner_race_diameter_m = 190e-3",
        ),
        "bearings[0].inner_race_diameter_m",
        |k| matches!(k, InvalidKind::DiameterOrder { .. }),
    );
    check(
        &edited("element_count = 22", "element_count = 2"),
        "bearings[0].element_count",
        |k| matches!(k, InvalidKind::OutOfRange { .. }),
    );
    check(
        &edited("roller_length_m = 16e-3\n", ""),
        "bearings[2].roller_length_m",
        |k| matches!(k, InvalidKind::MissingKey(_)),
    );
    check(
        &edited("initial_clearance_m = 5e-6", "initial_clearance_m = -5e-6"),
        "bearings[2].initial_clearance_m",
        |k| matches!(k, InvalidKind::OutOfRange { .. }),
    );
}

#[test]
fn damping_and_gravity_choices() {
    check(
        &edited(
            "damping_ratio = 0.0325\n",
            "damping_ratio = 0.0325\na0_1_s = 1.0\n",
        ),
        "damping",
        |k| matches!(k, InvalidKind::Conflict(_)),
    );
    // Gravity off: the bearings need an explicit linearisation.
    check(
        &edited("[gravity]\nenabled = true", "[gravity]\nenabled = false"),
        "bearings[0]",
        |k| matches!(k, InvalidKind::Conflict(_)),
    );
}

#[test]
fn file_errors_name_the_file() {
    let e = Model::from_file("/nonexistent/rotor.toml").expect_err("no such file");
    assert!(matches!(e, ModelError::Io { .. }));
    assert!(e.to_string().contains("/nonexistent/rotor.toml"));
    // the reason once, also where the whole chain is printed (`error: {:#}`)
    let chain = format!("{:#}", anyhow::Error::from(e));
    assert_eq!(chain.matches("os error").count(), 1, "{chain}");
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, edited("inner_node = 12", "inner_node = 40")).expect("write");
    let e = Model::from_file(&path).expect_err("bad file");
    let msg = e.to_string();
    assert!(
        msg.contains("bad.toml") && msg.contains("bearings[1].inner_node") && msg.contains("40")
    );
}

#[test]
fn thermal_table_is_kept_opaque() {
    // The mechanical part of the built-in file with a thermal table the model layer does
    // not understand: it is kept, not validated, here.
    let mech = BUILTIN_TOML
        .split("\n[thermal]\n")
        .next()
        .expect("text before the thermal section");
    let text = format!(
        "{mech}\n[thermal]\nnodes = 66\n[[thermal.resistances]]\nfrom = 1\nto = 2\nanything = \"goes\"\n"
    );
    let m = Model::from_str(&text, FILE).expect("valid");
    let t = m.thermal().expect("kept");
    assert_eq!(t.get("nodes").and_then(|v| v.as_integer()), Some(66));
    assert!(t.get("resistances").is_some());
}

/// A Jeffcott rotor as a new user writes it: a solid shaft, one disk, one ball bearing with
/// only the keys the mechanics needs (no geometry record, no `[thermal]`) and a linear
/// support. It loads, assembles and builds the coupled system.
#[test]
fn a_minimal_rotor_with_a_solid_shaft_and_one_ball_bearing_loads() {
    let text = r#"
name = "jeffcott"
[[materials]]
id = "steel"
youngs_modulus_pa = 2.1e11
poisson_ratio = 0.3
density_kg_m3 = 7850
[[rotors]]
id = "r"
nodes = [1, 2, 3]
[[shafts]]
nodes = [1, 2]
length_m = 0.3
inner_diameter_m = 0.0
outer_diameter_m = 0.03
material = "steel"
[[shafts]]
nodes = [2, 3]
length_m = 0.3
inner_diameter_m = 0.0
outer_diameter_m = 0.03
material = "steel"
[[disks]]
id = "d"
node = 2
mass_kg = 10
polar_inertia_kg_m2 = 0.05
diametral_inertia_kg_m2 = 0.025
eccentricity_m = 1e-5
[[supports]]
id = "s"
node = 3
stiffness_n_m = 1e7
[[bearings]]
id = "b"
kind = "ball"
inner_node = 1
material = "steel"
inner_race_diameter_m = 0.035
outer_race_diameter_m = 0.055
element_count = 9
hertz_stiffness = 1e9
initial_clearance_m = 5e-6
"#;
    let model = tmrotor::model::Model::from_str(text, "jeffcott.toml").expect("loads");
    let asm = tmrotor::model::Assembly::new(&model).expect("assembles");
    assert_eq!(asm.n_dof, 12);
    let coupled = tmrotor::coupled::CoupledRotor::new(
        &model,
        &Default::default(),
        tmrotor::coupled::CouplingOptions::default(),
    )
    .expect("coupled system");
    assert!(coupled.network().is_none());
    // a geometry record that is given is still checked
    let bad = text.replace(
        "inner_race_diameter_m = 0.035",
        "inner_race_diameter_m = 0.035\nbore_diameter_m = 0.04",
    );
    let err = tmrotor::model::Model::from_str(&bad, "jeffcott.toml")
        .expect_err("bore above the inner raceway")
        .to_string();
    assert!(err.contains("bore_diameter_m"), "{err}");
}

/// Values no engineering rotor has are refused with the range and its reason; the message
/// writes a huge number in exponent form.
#[test]
fn implausible_values_name_their_range() {
    let e = check(
        &edited("youngs_modulus_pa = 210e9", "youngs_modulus_pa = 1e300"),
        "materials[0].youngs_modulus_pa",
        |k| matches!(k, InvalidKind::OutOfRange { .. }),
    );
    assert!(e.to_string().contains("1e300 is out of range"), "{e}");
    check(
        &edited("initial_clearance_m = 1e-6", "initial_clearance_m = 1.0"),
        "bearings[0].initial_clearance_m",
        |k| matches!(k, InvalidKind::OutOfRange { .. }),
    );
}

/// The thermal network's speed ratios must be the rotors' (checked where the two tables
/// meet, when the coupled system is built: what `model check` and a sweep both do).
#[test]
fn thermal_speed_ratios_must_be_the_rotors() {
    use tmrotor::coupled::{CoupledRotor, CouplingOptions, StudyOverrides};
    let build = |text: &str| {
        let m = Model::from_str(text, FILE).expect("valid on its own");
        CoupledRotor::new(&m, &StudyOverrides::default(), CouplingOptions::default())
            .map(|_| ())
            .expect_err("refused")
            .to_string()
    };
    let msg = build(&BUILTIN_TOML.replace("speed_ratio = 1.2\n", "speed_ratio = 1.3\n"));
    assert!(
        msg.contains("thermal.shafts[") && msg.contains("rotor \"HP\" turns at 1.2"),
        "{msg}"
    );
    let msg = build(&edited(
        "inner_speed_ratio = 1.2\n",
        "inner_speed_ratio = 1.0\n",
    ));
    assert!(
        msg.contains("thermal.bearings[1].inner_speed_ratio")
            && msg.contains("bearing \"2#\" sits on node 12"),
        "{msg}"
    );
    let msg = build(&edited(
        "outer_speed_ratio = 0.0\n",
        "outer_speed_ratio = 1.0\n",
    ));
    assert!(
        msg.contains("thermal.bearings[0].outer_speed_ratio") && msg.contains("held by the ground"),
        "{msg}"
    );
}

/// Under gravity, a rotor that nothing holds (no support or bearing leads from it to the
/// ground) is named as such, not left to fail later as a static equilibrium that does not
/// converge.
#[test]
fn a_rotor_held_by_nothing_is_named() {
    let path = format!(
        "{}/examples/rotors/jeffcott_midspan_disk.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(path).expect("example rotor");
    let cut = text.find("[[supports]]").expect("the example has supports");
    let free = &text[..cut];
    // without gravity a free-free rotor is valid (its modes are a classic check)…
    Model::from_str(free, FILE).expect("free-free without gravity");
    // …under gravity it has no equilibrium
    let with_gravity = free.replacen("[gravity]\nenabled = false", "[gravity]\nenabled = true", 1);
    assert_ne!(with_gravity, free);
    let e = reject(&with_gravity);
    assert_eq!(e.path(), Some("rotors[0]"), "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains("is not held") && msg.contains("no static equilibrium"),
        "{msg}"
    );
}

/// A value the validator rejects (not the TOML parser) is reported with its line too.
#[test]
fn rejected_value_names_its_line() {
    let first = BUILTIN_TOML
        .lines()
        .find(|l| l.trim_start().starts_with("initial_clearance_m"))
        .expect("a clearance line");
    let text = edited(first, "initial_clearance_m = -1e-5");
    let line = text
        .lines()
        .position(|l| l == "initial_clearance_m = -1e-5")
        .expect("edited")
        + 1;
    let e = check(&text, "bearings[0].initial_clearance_m", |k| {
        matches!(k, InvalidKind::OutOfRange { .. })
    });
    match &e {
        ModelError::Invalid { line: l, .. } => assert_eq!(*l, Some(line), "{e}"),
        other => panic!("{other}"),
    }
    assert!(
        e.to_string().starts_with(&format!("{FILE}:{line}: ")),
        "{e}"
    );
}

/// Problems of single values do not stop the checks: all of them are reported at once,
/// in file order of the checks, each with its line.
#[test]
fn all_value_problems_are_reported_at_once_with_their_lines() {
    let density = BUILTIN_TOML
        .lines()
        .find(|l| l.trim_start().starts_with("density_kg_m3"))
        .expect("a density line");
    let clearance = BUILTIN_TOML
        .lines()
        .find(|l| l.trim_start().starts_with("initial_clearance_m"))
        .expect("a clearance line");
    let text = BUILTIN_TOML
        .replacen(density, "density_kg_m3 = -7800.0", 1)
        .replacen(clearance, "initial_clearance_m = -1e-5", 1);
    let line = |needle: &str| text.lines().position(|l| l == needle).expect("edited") + 1;
    let e = reject(&text);
    let problems = e.problems();
    assert_eq!(problems.len(), 2, "{e}");
    let msg = e.to_string();
    let lines: Vec<&str> = msg.lines().collect();
    assert_eq!(lines.len(), 2, "{msg}");
    assert!(
        lines[0].starts_with(&format!(
            "{FILE}:{}: materials[0].density_kg_m3",
            line("density_kg_m3 = -7800.0")
        )),
        "{msg}"
    );
    assert!(
        lines[1].starts_with(&format!(
            "{FILE}:{}: bearings[0].initial_clearance_m",
            line("initial_clearance_m = -1e-5")
        )),
        "{msg}"
    );
}

/// Structural problems of single elements (a shaft on a missing node, a duplicate disk id,
/// a bearing of an unknown material) do not stop the checks either: they come out with the
/// value problems, each with its line, and the whole-model checks they would spoil (every
/// node has mass, every rotor is held) are left out.
#[test]
fn structural_problems_of_elements_are_reported_together_with_their_lines() {
    let density = BUILTIN_TOML
        .lines()
        .find(|l| l.trim_start().starts_with("density_kg_m3"))
        .expect("a density line");
    let text = BUILTIN_TOML
        .replacen(density, "density_kg_m3 = -7800.0", 1)
        .replacen("nodes = [1, 2]", "nodes = [1, 999]", 1)
        .replacen("id = \"LPT\"", "id = \"LPC\"", 1)
        .replacen("material = \"bearing\"", "material = \"unobtainium\"", 1);
    // the last line so written (the duplicate id is the second `id = "LPC"`)
    let line = |needle: &str| {
        text.lines()
            .enumerate()
            .filter(|(_, l)| *l == needle)
            .last()
            .expect("edited")
            .0
            + 1
    };
    let e = reject(&text);
    let msg = e.to_string();
    let lines: Vec<&str> = msg.lines().collect();
    assert_eq!(lines.len(), 4, "{msg}");
    for (expected, needle) in [
        ("materials[0].density_kg_m3", "density_kg_m3 = -7800.0"),
        ("shafts[0].nodes[1]", "nodes = [1, 999]"),
        ("disks[1].id", "id = \"LPC\""),
        ("bearings[0].material", "material = \"unobtainium\""),
    ] {
        let want = format!("{FILE}:{}: {expected}", line(needle));
        assert!(
            lines.iter().any(|l| l.starts_with(&want)),
            "no line starts with {want:?}:\n{msg}"
        );
    }
    assert!(msg.contains("999") && msg.contains("unobtainium"), "{msg}");
}

/// The `[thermal]` table reports its value problems at once, each with the line of the
/// model file it is on, and a missing key with the line of its table's header.
#[test]
fn thermal_problems_carry_their_lines() {
    let run = |text: &str| {
        let model = Model::from_str(text, FILE).expect("mechanical part valid");
        tmrotor::coupled::CoupledRotor::new(
            &model,
            &tmrotor::coupled::StudyOverrides::default(),
            tmrotor::coupled::CouplingOptions::default(),
        )
        .map(|_| ())
        .expect_err("thermal table refused")
        .to_string()
    };
    let line =
        |text: &str, needle: &str| text.lines().position(|l| l == needle).expect("in file") + 1;

    let text = BUILTIN_TOML
        .replacen("nu0_mm2_s = 20.0", "nu0_mm2_s = -20.0", 1)
        .replacen(
            "specific_heat_j_kg_k = 1870.0",
            "specific_heat_j_kg_k = 0.0",
            1,
        );
    let msg = run(&text);
    let lines: Vec<&str> = msg.lines().collect();
    assert_eq!(lines.len(), 2, "{msg}");
    assert!(
        lines[0].starts_with(&format!(
            "{FILE}:{}: thermal.viscosity.nu0_mm2_s: ",
            line(&text, "nu0_mm2_s = -20.0")
        )),
        "{msg}"
    );
    assert!(
        lines[1].starts_with(&format!(
            "{FILE}:{}: thermal.lubricant.specific_heat_j_kg_k: ",
            line(&text, "specific_heat_j_kg_k = 0.0")
        )),
        "{msg}"
    );

    let text = BUILTIN_TOML.replacen("nu0_mm2_s = 20.0\n", "", 1);
    let msg = run(&text);
    assert_eq!(
        msg,
        format!(
            "{FILE}:{}: thermal.viscosity: missing field `nu0_mm2_s`",
            line(&text, "[thermal.viscosity]")
        )
    );
}

/// The ROSS reference rotor with a tabulated support (`tests/fixtures/ross`), edited.
fn table_rotor(from: &str, to: &str) -> String {
    let text = include_str!("fixtures/ross/speed_table.toml");
    assert!(text.contains(from), "fixture edit {from:?} not found");
    text.replacen(from, to, 1)
}

#[test]
fn support_table_speeds_must_increase() {
    let e = check(
        &table_rotor(
            "speeds_rad_s = [200.0, 1000.0]",
            "speeds_rad_s = [200.0, 100.0]",
        ),
        "supports[1].table.speeds_rad_s[1]",
        |k| matches!(k, InvalidKind::OutOfRange { .. }),
    );
    assert!(e.to_string().contains("increase strictly"), "{e}");
}

#[test]
fn support_table_needs_one_value_per_speed() {
    let e = check(
        &table_rotor(
            "kxy_n_m = [1.000000e+06, 9.000000e+06]",
            "kxy_n_m = [1.0e6, 9.0e6, 1.2e7]",
        ),
        "supports[1].table.kxy_n_m",
        |k| matches!(k, InvalidKind::BadConnection(_)),
    );
    assert!(e.to_string().contains("3 values for 2 speeds"), "{e}");
}

#[test]
fn support_table_and_constants_are_refused_together() {
    let e = check(
        &table_rotor(
            "node = 7\n",
            "node = 7\nstiffness_n_m = 1e7\ndamping_xy_n_s_m = 5.0\n",
        ),
        "supports[1].table",
        |k| matches!(k, InvalidKind::BadConnection(_)),
    );
    let msg = e.to_string();
    assert!(
        msg.contains("stiffness_n_m") && msg.contains("damping_xy_n_s_m"),
        "{msg}"
    );
}

#[test]
fn cross_coupled_coefficients_must_be_finite() {
    check(
        &table_rotor("stiffness_xy_n_m = 2.000000e+06", "stiffness_xy_n_m = nan"),
        "supports[0].stiffness_xy_n_m",
        |k| matches!(k, InvalidKind::OutOfRange { .. }),
    );
}

#[test]
fn tapered_element_end_diameters_are_checked() {
    let text = include_str!("fixtures/ross/tapered_1.toml");
    let from = "inner_diameter_end_m = 0.0\nouter_diameter_end_m = 0.06";
    assert!(text.contains(from));
    let e = check(
        &text.replacen(
            from,
            "inner_diameter_end_m = 0.07\nouter_diameter_end_m = 0.06",
            1,
        ),
        "shafts[1].inner_diameter_end_m",
        |k| matches!(k, InvalidKind::DiameterOrder { .. }),
    );
    assert!(e.to_string().contains("0.07"), "{e}");
    check(
        &text.replacen(
            from,
            "inner_diameter_end_m = 0.0\nouter_diameter_end_m = -0.06",
            1,
        ),
        "shafts[1].outer_diameter_end_m",
        |k| matches!(k, InvalidKind::NotPositive(_)),
    );
}

/// An element given backwards (`[9, 8]` between `[7, 8]` and `[9, 10]`) would fold the rotor
/// back over itself: refused, naming the element it overlaps. Listing the elements in
/// another order is fine.
#[test]
fn shaft_element_against_the_axis() {
    let e = check(
        &edited("nodes = [8, 9]", "nodes = [9, 8]"),
        "shafts[7].nodes",
        |k| matches!(k, InvalidKind::BadConnection(_)),
    );
    let msg = e.to_string();
    assert!(
        msg.contains("element 9–8") && msg.contains("shafts[6]"),
        "{msg}"
    );
    // the same elements in reverse file order are one rotor
    let start = BUILTIN_TOML.find("\n[[shafts]]").expect("shafts");
    let end = BUILTIN_TOML.find("\n[[disks]]").expect("disks");
    let mut blocks: Vec<&str> = BUILTIN_TOML[start..end]
        .split("\n[[shafts]]")
        .filter(|b| !b.trim().is_empty())
        .collect();
    blocks.reverse();
    let reordered = format!(
        "{}{}{}",
        &BUILTIN_TOML[..start],
        blocks
            .iter()
            .map(|b| format!("\n[[shafts]]{b}"))
            .collect::<String>(),
        &BUILTIN_TOML[end..]
    );
    assert_ne!(reordered, BUILTIN_TOML);
    Model::from_str(&reordered, FILE).expect("reordered elements are valid");
}

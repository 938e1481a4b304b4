//! The model-file reference against the code: every field of the serde structures of a
//! model file (mechanical and `[thermal]`) has exactly one entry in
//! `tmrotor::model::reference::KEYS` and vice versa; `docs/model-reference.md` is what
//! `tmrotor model reference` prints; each key the reference calls required is one the
//! loader asks for when it is missing from the built-in file, and each optional one is not;
//! each bound is enforced and each numeric default is the one the model computes with.

use std::collections::BTreeSet;

use serde::Deserialize;
use serde::de::{self, Deserializer, Visitor};
use tmrotor::model::file as mf;
use tmrotor::model::reference::{Bound, KEYS, Need, TABLES, markdown};
use tmrotor::thermal::generate as tg;
use tmrotor::thermal::spec as ts;

/// A deserializer that records the field names a derived `Deserialize` asks for and then
/// stops: the serde structures' own list of keys.
struct Fields(Vec<&'static str>);

#[derive(Debug)]
struct Stop;
impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("stop")
    }
}
impl std::error::Error for Stop {}
impl de::Error for Stop {
    fn custom<T: std::fmt::Display>(_: T) -> Self {
        Stop
    }
}

impl<'de> Deserializer<'de> for &mut Fields {
    type Error = Stop;
    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Stop> {
        Err(Stop)
    }
    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _: &'static str,
        fields: &'static [&'static str],
        _: V,
    ) -> Result<V::Value, Stop> {
        self.0.extend_from_slice(fields);
        Err(Stop)
    }
    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 u8 u16 u32 u64 f32 f64 char str string bytes byte_buf option
        unit unit_struct newtype_struct seq tuple tuple_struct map enum identifier
        ignored_any
    }
}

fn fields<T: for<'de> Deserialize<'de>>() -> BTreeSet<&'static str> {
    let mut f = Fields(Vec::new());
    let _ = T::deserialize(&mut f);
    assert!(!f.0.is_empty(), "no fields recorded");
    f.0.into_iter().collect()
}

fn structs() -> Vec<(&'static str, BTreeSet<&'static str>)> {
    vec![
        ("", fields::<mf::ModelFile>()),
        ("gravity", fields::<mf::GravitySpec>()),
        ("damping", fields::<mf::DampingSpec>()),
        ("materials", fields::<mf::MaterialSpec>()),
        ("rotors", fields::<mf::RotorSpec>()),
        ("shafts", fields::<mf::ShaftSpec>()),
        ("disks", fields::<mf::DiskSpec>()),
        ("supports", fields::<mf::SupportSpec>()),
        ("supports.table", fields::<mf::SupportTableSpec>()),
        ("nonlinear", fields::<mf::NonlinearSpec>()),
        ("forces", fields::<mf::ForceSpec>()),
        ("bearings", fields::<mf::BearingSpec>()),
        ("thermal", fields::<ts::ThermalSpec>()),
        ("thermal.viscosity", fields::<ts::ViscositySpec>()),
        ("thermal.lubricant", fields::<ts::LubricantSpec>()),
        ("thermal.air", fields::<ts::AirSpec>()),
        ("thermal.materials", fields::<ts::MaterialsSpec>()),
        ("thermal.materials.bearing", fields::<ts::MaterialSpec>()),
        ("thermal.materials.shaft", fields::<ts::MaterialSpec>()),
        ("thermal.shafts", fields::<ts::ShaftSpec>()),
        ("thermal.disks", fields::<ts::DiskSpec>()),
        ("thermal.housings", fields::<ts::HousingSpec>()),
        ("thermal.bearings", fields::<ts::BearingThermalSpec>()),
        ("thermal.bearings.heat_split", fields::<ts::HeatSplit>()),
        ("thermal (generated)", fields::<tg::GeneratedThermal>()),
        (
            "thermal.ball_bearings, thermal.roller_bearings",
            fields::<tg::KindSettings>(),
        ),
        (
            "thermal.bearings (generated)",
            fields::<tg::BearingSettings>(),
        ),
    ]
}

#[test]
fn every_key_of_the_loader_has_one_entry_and_every_entry_is_a_key() {
    let tables: BTreeSet<&str> = TABLES.iter().map(|t| t.0).collect();
    for k in KEYS {
        assert!(
            tables.contains(k.table),
            "{}.{}: unknown table",
            k.table,
            k.key
        );
        assert!(!k.meaning.is_empty(), "{}.{}: no meaning", k.table, k.key);
        if k.need == Need::Optional {
            assert!(
                !k.default.is_empty(),
                "{}.{}: optional without a default",
                k.table,
                k.key
            );
        }
    }
    for (table, want) in structs() {
        let listed: Vec<&str> = KEYS
            .iter()
            .filter(|k| k.table == table)
            .map(|k| k.key)
            .collect();
        let got: BTreeSet<&str> = listed.iter().copied().collect();
        assert_eq!(got.len(), listed.len(), "[{table}]: a key listed twice");
        let missing: Vec<_> = want.difference(&got).collect();
        let extra: Vec<_> = got.difference(&want).collect();
        assert!(
            missing.is_empty() && extra.is_empty(),
            "[{table}]: keys without an entry {missing:?}, entries without a key {extra:?}"
        );
    }
}

#[test]
fn the_document_is_the_generated_reference() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/model-reference.md");
    let doc = std::fs::read_to_string(path).expect("docs/model-reference.md");
    assert!(
        doc == markdown(),
        "docs/model-reference.md is out of date: regenerate it with \
         `cargo run --release -- model reference > docs/model-reference.md`"
    );
}

/// Removes the first `key = …` line of the `[[table]]` whose header is `header` in `text`.
fn without_key(text: &str, header: &str, key: &str) -> Option<String> {
    let start = text.find(&format!("\n{header}\n"))?;
    let body = start + header.len() + 2;
    let end = text[body..].find("\n[").map_or(text.len(), |e| body + e);
    let line_start = text[body..end]
        .find(&format!("\n{key} = "))
        .map(|i| body + i + 1)
        .or_else(|| {
            text[body..end]
                .starts_with(&format!("{key} = "))
                .then_some(body)
        })?;
    let line_end = text[line_start..]
        .find('\n')
        .map_or(text.len(), |e| line_start + e + 1);
    Some(format!("{}{}", &text[..line_start], &text[line_end..]))
}

/// Each scalar key of the mechanical tables marked required makes the loader report a
/// missing key when removed from the built-in file; each marked optional does not.
#[test]
fn required_means_the_loader_asks_for_it() {
    let text = tmrotor::model::BUILTIN_TOML;
    let mut tried = 0;
    for k in KEYS
        .iter()
        .filter(|k| !k.table.starts_with("thermal") && !k.table.is_empty())
    {
        let header = if matches!(k.table, "gravity" | "damping") {
            format!("[{}]", k.table)
        } else {
            format!("[[{}]]", k.table)
        };
        let Some(cut) = without_key(text, &header, k.key) else {
            continue;
        };
        tried += 1;
        let result = tmrotor::model::Model::from_str(&cut, "cut.toml");
        let missing = match &result {
            Err(e) => {
                let m = e.to_string();
                m.contains("missing") && m.contains(k.key)
            }
            Ok(_) => false,
        };
        match k.need {
            Need::Required => assert!(
                missing,
                "{}.{} is required, but: {result:?}",
                k.table, k.key
            ),
            Need::Optional => assert!(
                !missing,
                "{}.{} is optional, but: {result:?}",
                k.table, k.key
            ),
            _ => {}
        }
    }
    assert!(tried >= 30, "only {tried} keys tried");
}

/// The shipped model files and their TOML.
fn shipped_models() -> Vec<(std::path::PathBuf, toml::Table)> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for dir in ["models", "examples/rotors"] {
        let mut names: Vec<_> = std::fs::read_dir(root.join(dir))
            .expect("model directory")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        names.sort();
        for path in names {
            let text = std::fs::read_to_string(&path).expect("model file");
            let table: toml::Table = toml::from_str(&text).expect("model TOML");
            files.push((path, table));
        }
    }
    files
}

/// Every table of every shipped model, with its file.
fn places(models: &[(std::path::PathBuf, toml::Table)]) -> Vec<(&std::path::Path, Instance)> {
    let mut places = Vec::new();
    for (path, table) in models {
        let generated = table
            .get("thermal")
            .and_then(|t| t.get("generate"))
            .and_then(toml::Value::as_bool)
            .unwrap_or(false);
        let mut found = Vec::new();
        instances(table, "", "", generated, &mut found);
        places.extend(found.into_iter().map(|i| (path.as_path(), i)));
    }
    places
}

/// One table of a model file: its path with indices (`thermal.bearings[2]`, `""` at the
/// top level), the reference's name of its table, and its keys.
struct Instance {
    at: String,
    table: String,
    keys: BTreeSet<String>,
}

/// Every table of `table` (itself included), depth first.
fn instances(
    table: &toml::Table,
    at: &str,
    section: &str,
    generated: bool,
    out: &mut Vec<Instance>,
) {
    out.push(Instance {
        at: at.to_string(),
        table: reference_table(section, generated),
        keys: table.keys().cloned().collect(),
    });
    for (k, v) in table {
        let path = if at.is_empty() {
            k.clone()
        } else {
            format!("{at}.{k}")
        };
        let sub = if section.is_empty() {
            k.clone()
        } else {
            format!("{section}.{k}")
        };
        match v {
            toml::Value::Table(t) => instances(t, &path, &sub, generated, out),
            toml::Value::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    if let toml::Value::Table(t) = item {
                        instances(t, &format!("{path}[{i}]"), &sub, generated, out);
                    }
                }
            }
            _ => {}
        }
    }
}

/// The reference's table name of the TOML table `section` (`thermal.bearings`).
fn reference_table(section: &str, generated: bool) -> String {
    match (section, generated) {
        ("thermal", true) => "thermal (generated)".into(),
        ("thermal.bearings", true) => "thermal.bearings (generated)".into(),
        ("thermal.ball_bearings" | "thermal.roller_bearings", _) => {
            "thermal.ball_bearings, thermal.roller_bearings".into()
        }
        (s, _) => s.into(),
    }
}

/// Values just outside a bound (each one the loader must refuse).
fn outside(bound: Bound) -> Vec<f64> {
    match bound {
        Bound::Free => vec![],
        Bound::Positive => vec![0.0, -1.0, f64::INFINITY],
        Bound::NonNegative => vec![-1e-9, f64::INFINITY],
        Bound::Finite => vec![f64::INFINITY, f64::NEG_INFINITY],
        Bound::Within {
            low,
            low_open,
            high,
            high_open,
        } => {
            let below = if low_open {
                low
            } else {
                low - 1e-9 * low.abs().max(1.0)
            };
            let above = if high_open {
                high
            } else {
                high + 1e-9 * high.abs().max(1.0)
            };
            vec![below, above]
        }
    }
}

/// Loads `file` with `path = value` as a sweep does (the model, then the coupled rotor
/// with its thermal network); the error's text when refused.
fn load_with(file: &std::path::Path, path: &str, value: f64) -> Result<(), String> {
    let set = tmrotor::model::ModelSet::from([(path.to_string(), toml::Value::Float(value))]);
    let model = tmrotor::model::Model::load(Some(file), &set).map_err(|e| e.to_string())?;
    tmrotor::coupled::CoupledRotor::new(&model, &Default::default(), Default::default())
        .map(|_| ())
        .map_err(|e| e.to_string())
}

/// Each bound the reference gives (its "checked" column's `> 0`, `≥ 0`, `finite`, `in
/// [a, b]`) is one the loader enforces. For every key with a bound: in the first shipped
/// model file that gives it (or, failing that, in a table of a shipped file where it may
/// be added and a value inside the bound loads), values just outside the bound are set
/// by path, and loading as a sweep does must refuse each, naming that path.
#[test]
fn every_bound_of_the_reference_is_enforced_by_the_loader() {
    let models = shipped_models();
    let places = places(&models);
    let mut unmet = Vec::new();
    let mut tried = 0;
    for key in KEYS.iter().filter(|k| k.bound != Bound::Free) {
        let named = |i: &Instance| match i.at.as_str() {
            "" => key.key.to_string(),
            at => format!("{at}.{}", key.key),
        };
        // a file that gives the key, else one where a value inside the bound can be added
        let given = places
            .iter()
            .find(|(_, i)| i.table == key.table && i.keys.contains(key.key));
        let place = given.or_else(|| {
            places.iter().find(|(file, i)| {
                i.table == key.table
                    && [0.0, 1e-3, 1.0]
                        .iter()
                        .any(|&v| key.bound.admits(v) && load_with(file, &named(i), v).is_ok())
            })
        });
        let Some((file, instance)) = place else {
            unmet.push(format!("{}.{}", key.table, key.key));
            continue;
        };
        let at = named(instance);
        for bad in outside(key.bound) {
            match load_with(file, &at, bad) {
                Err(message) => assert!(
                    message.contains(&at),
                    "{}: {at} = {bad} refused without naming it: {message}",
                    file.display()
                ),
                Ok(()) => panic!(
                    "{}: {at} = {bad} accepted, but the reference says {}",
                    file.display(),
                    key.checked()
                ),
            }
            tried += 1;
        }
    }
    assert!(
        unmet.is_empty(),
        "bounded keys met in no shipped model: {unmet:?}"
    );
    eprintln!("{tried} values outside their bounds refused, naming their paths");
}

/// What a model computes, for comparing two files: the coupled rotor a sweep builds from
/// it, as its linear matrices at ω = 300 rad/s, its external and thermal loads, and its
/// nonlinear forces and heat with their derivatives at one fixed state (small
/// displacements and velocities, temperatures a few kelvin above ambient), at three
/// instants.
fn loaded(file: &std::path::Path, set: &tmrotor::model::ModelSet) -> Option<String> {
    use tmrotor::system::{NonlinearEval, System};
    let model = tmrotor::model::Model::load(Some(file), set).ok()?;
    let rotor =
        tmrotor::coupled::CoupledRotor::new(&model, &Default::default(), Default::default())
            .ok()?;
    let omega = 300.0;
    let dofs = rotor.nonlinear_dofs();
    let (p, q) = (dofs.mech.len(), dofs.therm.len());
    let x: Vec<f64> = (0..p).map(|i| 1e-5 * ((i % 7) as f64 - 3.0)).collect();
    let v: Vec<f64> = (0..p).map(|i| 1e-3 * ((i % 5) as f64 - 2.0)).collect();
    let temp: Vec<f64> = (0..q).map(|i| 25.0 + (i % 4) as f64).collect();
    let mut out = format!("{:?}", rotor.linear(omega));
    for t in [0.0, 0.004, 0.011] {
        let mut eval = NonlinearEval::new(p, q);
        rotor.eval_nonlinear(omega, t, &x, &v, &temp, &mut eval);
        let mut force = vec![0.0; rotor.n_mech()];
        rotor.forcing(omega, t, &mut force);
        out += &format!(
            "\n{:?} {:?} {:?} {:?} {force:?}",
            eval.f, eval.g, eval.df_dx, eval.dg_dt
        );
    }
    let mut heat = vec![0.0; rotor.n_therm()];
    rotor.thermal_load(omega, &mut heat);
    out += &format!("\n{heat:?}");
    Some(out)
}

/// The model file `file` with the key at `path` (`thermal.bearings[2].f_v`) taken out,
/// as TOML text.
fn without_path(file: &std::path::Path, path: &str) -> String {
    let text = std::fs::read_to_string(file).expect("model file");
    let mut table: toml::Table = toml::from_str(&text).expect("model TOML");
    let parts: Vec<&str> = path.split('.').collect();
    let mut at = &mut table;
    for part in &parts[..parts.len() - 1] {
        let (name, index) = match part.split_once('[') {
            Some((n, i)) => (
                n,
                Some(i.trim_end_matches(']').parse::<usize>().expect("index")),
            ),
            None => (*part, None),
        };
        let value = at.get_mut(name).expect("table on the path");
        let value = match index {
            Some(i) => &mut value.as_array_mut().expect("array")[i],
            None => value,
        };
        at = value.as_table_mut().expect("table");
    }
    at.remove(parts[parts.len() - 1]);
    toml::to_string(&table).expect("TOML")
}

/// For keys that cannot be left out one at a time (the heat split's fractions must sum to
/// 1): a shipped table of `table` taken out of its file, against the same table with every
/// key written with its numeric default. (file, the table's path, with, without).
fn whole_table<'a>(
    places: &[(&'a std::path::Path, Instance)],
    table: &str,
) -> Option<(&'a std::path::Path, String, String, String)> {
    let keys: Vec<(&str, f64)> = KEYS
        .iter()
        .filter(|k| k.table == table)
        .map(|k| Some((k.key, k.default.parse::<f64>().ok()?)))
        .collect::<Option<_>>()?;
    places.iter().find_map(|&(file, ref i)| {
        if i.table != table {
            return None;
        }
        let set: tmrotor::model::ModelSet = keys
            .iter()
            .map(|&(k, v)| (format!("{}.{k}", i.at), toml::Value::Float(v)))
            .collect();
        let with_keys = loaded(file, &set)?;
        let dir = tempfile::tempdir().expect("temporary directory");
        let cut = dir.path().join("cut.toml");
        std::fs::write(&cut, without_path(file, &i.at)).expect("write");
        let without = loaded(&cut, &Default::default())?;
        Some((file, i.at.clone(), with_keys, without))
    })
}

/// Each number the reference gives as a key's default is the loader's: in a table of a
/// shipped model file that leaves the key out (or else one that gives it, the key then
/// taken out), the file computes the same as with the key written with that number.
#[test]
fn every_numeric_default_of_the_reference_is_the_loaders() {
    let models = shipped_models();
    let places = places(&models);
    let mut unmet = Vec::new();
    let mut tried = 0;
    for key in KEYS.iter().filter(|k| k.need == Need::Optional) {
        let Ok(default) = key.default.parse::<f64>() else {
            continue;
        };
        let path_in = |i: &Instance| match i.at.as_str() {
            "" => key.key.to_string(),
            at => format!("{at}.{}", key.key),
        };
        let written = |i: &Instance| {
            tmrotor::model::ModelSet::from([(path_in(i), toml::Value::Float(default))])
        };
        // a table that leaves the key out and where writing it is allowed, else one that
        // gives it, the key then taken out of the file
        let compared = places.iter().find_map(|(file, i)| {
            if i.table != key.table {
                return None;
            }
            let with_key = loaded(file, &written(i))?;
            let without = if i.keys.contains(key.key) {
                let dir = tempfile::tempdir().expect("temporary directory");
                let cut = dir.path().join("cut.toml");
                std::fs::write(&cut, without_path(file, &path_in(i))).expect("write");
                loaded(&cut, &Default::default())?
            } else {
                loaded(file, &Default::default())?
            };
            Some((*file, path_in(i), with_key, without))
        });
        let Some((file, path, with_key, without)) =
            compared.or_else(|| whole_table(&places, key.table))
        else {
            unmet.push(format!("{}.{}", key.table, key.key));
            continue;
        };
        assert_eq!(
            without,
            with_key,
            "{}: leaving out {path} is not the same as {path} = {default}",
            file.display()
        );
        tried += 1;
    }
    assert!(
        unmet.is_empty(),
        "numeric defaults left out in no shipped model: {unmet:?}"
    );
    eprintln!("{tried} numeric defaults are the loader's");
}

//! Figures: every kind of `replay plot` as PNG and SVG (from the synthetic recording and a
//! short real sweep), and the placement of bifurcation labels in a six-run campaign overlay
//! checked on geometry.

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::{has_colour, png_pixels, replay_in_process};

use tmrotor::campaign::{self, sha256_file};
use tmrotor::figure::campaign::{FigureOptions, plot_campaign};
use tmrotor::figure::{self, Format, NOT_ASSESSED, Output, PixelBox, STABLE, UNSTABLE};
use tmrotor::record::synthetic::{self, SyntheticOptions};

/// A small well-formedness check of XML: one root element, every tag closed in order,
/// attribute values quoted, `&` only in entities. Returns the text content.
fn check_xml(text: &str) -> Result<String, String> {
    let mut stack: Vec<String> = Vec::new();
    let mut content = String::new();
    let mut rest = text.trim_start();
    let mut roots = 0;
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix("<?") {
            let end = r.find("?>").ok_or("unclosed <?")?;
            rest = &r[end + 2..];
        } else if let Some(r) = rest.strip_prefix("<!--") {
            let end = r.find("-->").ok_or("unclosed comment")?;
            rest = &r[end + 3..];
        } else if let Some(r) = rest.strip_prefix("</") {
            let end = r.find('>').ok_or("unclosed end tag")?;
            let name = r[..end].trim();
            match stack.pop() {
                Some(open) if open == name => {}
                other => return Err(format!("</{name}> closes {other:?}")),
            }
            rest = &r[end + 1..];
        } else if let Some(r) = rest.strip_prefix('<') {
            // a start tag: name, then attributes name="value" up to > or />
            let name_end = r
                .find(|c: char| c.is_whitespace() || c == '>' || c == '/')
                .ok_or("bad tag")?;
            let name = &r[..name_end];
            if name.is_empty() {
                return Err("empty tag name".into());
            }
            let mut a = &r[name_end..];
            let closed = loop {
                a = a.trim_start();
                if let Some(x) = a.strip_prefix("/>") {
                    a = x;
                    break true;
                }
                if let Some(x) = a.strip_prefix('>') {
                    a = x;
                    break false;
                }
                let eq = a
                    .find('=')
                    .ok_or_else(|| format!("attribute without = in <{name}>"))?;
                let after = a[eq + 1..].trim_start();
                let quote = after.chars().next().ok_or("attribute value missing")?;
                if quote != '"' && quote != '\'' {
                    return Err(format!("unquoted attribute in <{name}>"));
                }
                let close = after[1..].find(quote).ok_or("unclosed attribute value")?;
                a = &after[close + 2..];
            };
            if stack.is_empty() {
                roots += 1;
            }
            if !closed {
                stack.push(name.to_string());
            }
            rest = a;
        } else {
            let end = rest.find('<').unwrap_or(rest.len());
            let t = &rest[..end];
            for (i, _) in t.match_indices('&') {
                let entity = &t[i..t[i..].find(';').map_or(t.len(), |e| i + e + 1)];
                if !["&amp;", "&lt;", "&gt;", "&quot;", "&apos;"].contains(&entity)
                    && !entity.starts_with("&#")
                {
                    return Err(format!("bad entity {entity:?}"));
                }
            }
            if stack.is_empty() && !t.trim().is_empty() {
                return Err("text outside the root element".into());
            }
            content.push_str(t);
            rest = &rest[end..];
        }
    }
    match (stack.is_empty(), roots) {
        (true, 1) => Ok(content),
        (false, _) => Err(format!("unclosed elements {stack:?}")),
        (_, n) => Err(format!("{n} root elements")),
    }
}

/// Checks that `dir/name.svg` is XML holding every one of `texts`, and that `name.png` exists.
fn check_svg(dir: &Path, name: &str, texts: &[&str]) {
    let svg = dir.join(format!("{name}.svg"));
    let text = std::fs::read_to_string(&svg).unwrap_or_else(|e| panic!("{}: {e}", svg.display()));
    let content = check_xml(&text).unwrap_or_else(|e| panic!("{name}.svg is not XML: {e}"));
    for t in texts {
        assert!(content.contains(t), "{name}.svg lacks the text {t:?}");
    }
    assert!(dir.join(format!("{name}.png")).exists(), "{name}.png");
}

#[test]
fn the_xml_check_finds_broken_files() {
    assert!(check_xml("<svg a=\"1\"><text>x &amp; y</text><g/></svg>").is_ok());
    assert!(check_xml("<svg><text>x</svg>").is_err());
    assert!(check_xml("<svg a=1></svg>").is_err());
    assert!(check_xml("<svg>a & b</svg>").is_err());
    assert!(check_xml("<a/><b/>").is_err());
}

#[test]
fn replay_plot_writes_every_kind_as_png_and_svg_from_the_synthetic_recording() {
    if figure::font().is_none() {
        eprintln!("no font: skipped (figures would carry no text)");
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let rec = dir.path().join("run.mcap");
    let options = SyntheticOptions {
        points_per_side: 10,
        ..Default::default()
    };
    synthetic::write_mcap(&rec, &options, true).expect("write");
    let figs = dir.path().join("figs");
    let (rec_s, figs_s) = (rec.to_string_lossy(), figs.to_string_lossy());
    let (res, out, err) = replay_in_process(&["plot", &rec_s, "--out", &figs_s, "--point", "3"]);
    assert!(res.is_ok(), "{res:?}\n{err}");
    // the synthetic model cannot be rebuilt: the recorded load samples are drawn
    assert!(err.contains("drawn from the recorded samples"), "{err}");
    let y = "RMS amplitude, node 1 (disk) (µm)";
    let temp = "mean temperature, bearing 1# rolling elements (thermal node 52) (°C)";
    for (name, texts) in [
        (
            "amplitude_node1",
            vec![y, "speed ω (rad/s)", "SN1", "stable", "unstable"],
        ),
        (
            "clearance",
            vec!["radial clearance variation δv (µm)", "bearing 1#"],
        ),
        (
            "temperatures",
            vec!["mean temperature (°C)", "rolling elements"],
        ),
        ("temperature_node52", vec![temp, "SN2"]),
        (
            "multipliers_bifurcations",
            vec!["Re μ", "Im μ", "unit circle", "point before", "SN1 at ω ="],
        ),
        ("multipliers_point3", vec!["Re μ", "multipliers of point 3"]),
        (
            "orbits_peaks",
            vec![
                "horizontal displacement y (µm)",
                "vertical displacement x (µm)",
                "LP rotor",
            ],
        ),
        (
            "bearing_loads_point3",
            vec!["radial bearing load (N)", "revolutions"],
        ),
        (
            "bearing_loads_mean",
            vec!["radial load (N)", "lowest and highest"],
        ),
    ] {
        check_svg(&figs, name, &texts);
        assert!(out.contains(&format!("{name}.svg")), "{out}");
    }
    // no title by default; --title draws it
    let amp = std::fs::read_to_string(figs.join("amplitude_node1.svg")).expect("svg");
    assert!(!amp.contains("Amplitude–frequency response"));
    // stability colours in the branch figures
    for name in [
        "amplitude_node1",
        "temperature_node52",
        "bearing_loads_mean",
    ] {
        let (_, _, px) = png_pixels(&figs.join(format!("{name}.png")));
        assert!(has_colour(&px, STABLE), "{name}: stable colour");
        assert!(has_colour(&px, UNSTABLE), "{name}: unstable colour");
    }

    let titled = dir.path().join("titled");
    let (res, _, err) = replay_in_process(&[
        "plot",
        &rec_s,
        "--out",
        &titled.to_string_lossy(),
        "--format",
        "svg",
        "--title",
    ]);
    assert!(res.is_ok(), "{err}");
    let amp = std::fs::read_to_string(titled.join("amplitude_node1.svg")).expect("svg");
    assert!(amp.contains("Amplitude–frequency response"));
    assert!(!titled.join("amplitude_node1.png").exists(), "svg only");

    // a recording without stability: grey, "not assessed"
    let plain = dir.path().join("plain.mcap");
    let options = SyntheticOptions {
        stability: false,
        ..options
    };
    synthetic::write_mcap(&plain, &options, true).expect("write");
    let out3 = dir.path().join("plain");
    let (res, _, err) = replay_in_process(&[
        "plot",
        &plain.to_string_lossy(),
        "--out",
        &out3.to_string_lossy(),
        "--format",
        "png",
    ]);
    assert!(res.is_ok(), "{err}");
    let (_, _, px) = png_pixels(&out3.join("amplitude_node1.png"));
    assert!(has_colour(&px, NOT_ASSESSED) && !has_colour(&px, UNSTABLE));

    // bad flags say what is wrong
    for (args, want) in [
        (vec!["--format", "pdf"], "rsvg-convert"),
        (vec!["--node", "99"], "no dynamic node 99"),
        (vec!["--thermal-node", "7"], "no thermal node 7"),
        (vec!["--point", "999"], "no point 999"),
    ] {
        let mut all = vec!["plot", &*rec_s, "--out", &*figs_s];
        all.extend(args);
        let (res, _, _) = replay_in_process(&all);
        let msg = format!("{:#}", res.expect_err("bad flag"));
        assert!(msg.contains(want), "{msg}");
    }
}

/// A short sweep of the built-in dual rotor across its first resonance (order 1, lean: no
/// /orbits): orbits come from the harmonic coefficients and bearing loads through the
/// embedded model.
#[test]
fn replay_plot_rederives_orbits_and_loads_of_a_lean_real_sweep() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rec = dir.path().join("short.mcap");
    let made = Command::new(env!("CARGO_BIN_EXE_tmrotor"))
        .args([
            "sweep",
            "--order",
            "1",
            "--omega",
            "405:460",
            "--max-points",
            "30",
        ])
        .args(["--lean", "-q", "-o"])
        .arg(&rec)
        .output()
        .expect("sweep");
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let figs = dir.path().join("figs");
    let (res, _, err) = replay_in_process(&[
        "plot",
        &rec.to_string_lossy(),
        "--out",
        &figs.to_string_lossy(),
    ]);
    assert!(res.is_ok(), "{err}");
    assert!(
        !err.contains("recorded samples"),
        "re-derived through the model: {err}"
    );
    if figure::font().is_none() {
        return;
    }
    check_svg(
        &figs,
        "orbits_peaks",
        &["LP rotor, peak at ω =", "HP rotor", "node 8"],
    );
    let loads: Vec<PathBuf> = std::fs::read_dir(&figs)
        .expect("dir")
        .filter_map(|e| Some(e.ok()?.path()))
        .filter(|p| p.to_string_lossy().contains("bearing_loads_point"))
        .collect();
    assert_eq!(loads.len(), 2, "{loads:?}");
    check_svg(&figs, "bearing_loads_mean", &["bearing 4#"]);
    check_svg(
        &figs,
        "temperature_node58",
        &["mean temperature, 3# rolling elements (thermal node 58) (°C)"],
    );
    check_svg(
        &figs,
        "temperatures",
        &[
            "bearing 2#",
            "shafts and disks",
            "LP shaft",
            "housing flanks",
        ],
    );
}

/// Six runs overlaid, their bifurcations crowding the same places: no label covers another
/// label or the legend, every label lies inside its plot area, and some are placed.
#[test]
fn campaign_labels_do_not_collide_in_a_six_run_overlay() {
    if figure::font().is_none() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let mut manifest = campaign::Manifest::default();
    for (k, points) in [6, 7, 8, 9, 11, 14].into_iter().enumerate() {
        let name = format!("r{k}");
        let rec = dir.path().join(format!("{name}.mcap"));
        let options = SyntheticOptions {
            points_per_side: points,
            ..Default::default()
        };
        synthetic::write_mcap(&rec, &options, true).expect("write");
        let mut settings = toml::Table::new();
        settings.insert(
            "flow_l_min".into(),
            toml::Value::Float(20.0 / (k + 1) as f64),
        );
        manifest.runs.push(campaign::ManifestEntry {
            name: name.clone(),
            status: "completed".into(),
            recording: format!("{name}.mcap"),
            sha256: sha256_file(&rec).expect("sha"),
            settings,
            ..Default::default()
        });
    }
    std::fs::write(
        dir.path().join("manifest.toml"),
        toml::to_string(&manifest).expect("toml"),
    )
    .expect("manifest");
    let options = FigureOptions {
        per_run: true,
        thermal_node: Some(52),
        output: Output {
            formats: vec![Format::Svg],
            title: false,
        },
        ..FigureOptions::default()
    };
    let figs = dir.path().join("figs");
    let done = plot_campaign(dir.path(), &figs, &options).expect("plot");
    let layout = |stem: &str| {
        done.layouts
            .iter()
            .find(|(s, _)| s == stem)
            .map(|(_, l)| l.clone())
            .unwrap_or_else(|| panic!("{stem} not drawn: {:?}", done.written))
    };
    for stem in [
        "amplitude_node1",
        "amplitude_node1_per_run",
        "temperature_node52",
        "temperature_node52_per_run",
    ] {
        let l = layout(stem);
        let legend = l.legend.expect("a legend");
        let mut labels: Vec<PixelBox> = Vec::new();
        for p in &l.panels {
            assert!(!legend.overlaps(&p.plot), "{stem}: legend over a plot area");
            for b in p.labels.iter().flatten() {
                assert!(
                    p.plot.contains(b),
                    "{stem}: label {b:?} outside {:?}",
                    p.plot
                );
                labels.push(*b);
            }
        }
        assert!(!labels.is_empty(), "{stem}: no label placed");
        for (i, a) in labels.iter().enumerate() {
            assert!(!a.overlaps(&legend), "{stem}: label {a:?} over the legend");
            for b in &labels[i + 1..] {
                assert!(!a.overlaps(b), "{stem}: labels {a:?} and {b:?} overlap");
            }
        }
    }
    // small multiples: a panel per run, all of one size on shared axes
    let per_run = layout("amplitude_node1_per_run");
    assert_eq!(per_run.panels.len(), 6);
    let size = |b: &PixelBox| (b.x1 - b.x0, b.y1 - b.y0);
    let first = size(&per_run.panels[0].plot);
    assert!(
        per_run
            .panels
            .iter()
            .all(|p| (size(&p.plot).0 - first.0).abs() <= 2
                && (size(&p.plot).1 - first.1).abs() <= 2),
        "{per_run:?}"
    );
    check_svg_only(
        &figs.join("amplitude_node1_per_run.svg"),
        "RMS amplitude (µm)",
    );
}

fn check_svg_only(path: &Path, text: &str) {
    let t = std::fs::read_to_string(path).expect("svg");
    let content = check_xml(&t).expect("xml");
    assert!(content.contains(text), "{}: {text}", path.display());
}

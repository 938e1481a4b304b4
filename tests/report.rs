//! The reproduction report from a small campaign: every run appears with the values its
//! recording holds, and a missing manifest is named in the error.

use tmrotor::campaign;
use tmrotor::record::reader::read_recording;
use tmrotor::report::{campaign_findings, markdown};

#[test]
fn report_reads_a_campaign_and_names_missing_input() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("c.toml");
    std::fs::write(
        &file,
        r#"
output_dir = "out"
[defaults]
order = 1
omega_start = 400.0
omega_end = 420.0
max_points = 12
stability = false
[[runs]]
name = "fast"
flow_l_min = 20.0
[[runs]]
name = "slow"
flow_l_min = 2.0
"#,
    )
    .expect("write campaign");
    let quiet = |_: &str, _: &tmrotor::sweep::Progress| {};
    let m = campaign::run(&file, Some(2), None, None, &quiet).expect("campaign");
    let out = dir.path().join("out");
    let runs = campaign_findings(&out).expect("findings");
    assert_eq!(runs.len(), 2);
    for (r, entry) in runs.iter().zip(&m.runs) {
        assert_eq!(r.name, entry.name);
        assert_eq!(r.points, entry.points);
        let rec = read_recording(out.join(&entry.recording)).expect("recording");
        // Largest |δv| per bearing equals the recording's own maximum.
        for (k, &m) in r.max_abs_dv_um.iter().enumerate() {
            let direct = rec
                .points
                .iter()
                .map(|p| p.clearances[k].delta_v_m.abs() * 1e6)
                .fold(0.0, f64::max);
            assert!((m - direct).abs() < 1e-12, "bearing {k}: {m} vs {direct}");
        }
        assert_eq!(r.assessed, 0, "stability was off");
    }
    let fast = runs.iter().find(|r| r.name == "fast").expect("fast");
    let slow = runs.iter().find(|r| r.name == "slow").expect("slow");
    assert_eq!((fast.flow_l_min, slow.flow_l_min), (20.0, 2.0));
    let md = markdown(
        &runs,
        "out",
        Some("| order | residual |\n|---|---|\n| 1 | 1e-3 |"),
    );
    assert!(md.contains("| fast | 20 | 25 |"), "{md}");
    assert!(md.contains("| slow | 2 | 25 |"), "{md}");
    assert!(md.contains("At 20 L/min"), "{md}");
    assert!(md.contains("## Truncation study"), "{md}");

    let err = campaign_findings(dir.path()).expect_err("no manifest there");
    assert!(err.to_string().contains("manifest.toml"), "{err}");
}

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
    let quiet = |_: tmrotor::campaign::Event<'_>| {};
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
    let csv = "target_rad_s,order,amplitude_node8_m,residual_node8_rms_n,residual_mech_rms_n,residual_therm_rms_w\n\
               400,1,2e-6,8.0,9.0,1.0\n400,2,2e-6,5.0,6.0,1.0\n400,3,2e-6,4.0,5.0,1.0\n\
               530,1,1e-5,200.0,210.0,1.0\n530,2,1e-5,250.0,260.0,1.0\n530,3,1e-5,100.0,110.0,1.0\n";
    let md = markdown(&runs, "out", Some(csv));
    assert!(md.contains("| fast | 20 | 25 |"), "{md}");
    assert!(md.contains("| slow | 2 | 25 |"), "{md}");
    assert!(md.contains("At 20 L/min"), "{md}");
    assert!(md.contains("## Truncation study"), "{md}");
    assert!(md.contains("| 400 | 8.000 → 5.000 → 4.000 | "), "{md}");
    assert!(md.contains("at 1 of 2 speeds — **partial**"), "{md}");

    let err = campaign_findings(dir.path()).expect_err("no manifest there");
    assert!(err.to_string().contains("manifest.toml"), "{err}");
}

//! Campaigns: parallel runs, manifest with checksums, resume, shards and merge.

use std::path::Path;

use tmrotor::campaign::{self, sha256_file};

fn write_campaign(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("c.toml");
    std::fs::write(
        &path,
        r#"
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
"#,
    )
    .expect("write campaign");
    path
}

#[test]
fn campaign_runs_resumes_shards_and_merges() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = write_campaign(dir.path());
    let quiet = |_: &str, _: &tmrotor::sweep::Progress| {};
    let m = campaign::run(&file, Some(2), None, None, &quiet).expect("campaign");
    assert_eq!(m.runs.len(), 3);
    let out = dir.path().join("out");
    for r in &m.runs {
        assert_eq!(r.status, "completed", "{r:?}");
        assert!(r.points >= 1);
        assert_eq!(
            sha256_file(&out.join(&r.recording)).expect("recording"),
            r.sha256
        );
    }
    // Resume: nothing changes, completed runs are skipped (same seconds as before).
    let again = campaign::run(&file, Some(2), None, None, &quiet).expect("resume");
    for (x, y) in m.runs.iter().zip(&again.runs) {
        assert_eq!(x.seconds, y.seconds, "run {} was redone", x.name);
    }
    // A damaged recording is redone.
    std::fs::write(out.join("b.mcap"), b"garbage").expect("damage");
    let redo = campaign::run(&file, Some(2), None, None, &quiet).expect("redo");
    let b = redo.runs.iter().find(|r| r.name == "b").expect("b");
    assert_ne!(b.sha256, sha256_file(&file).unwrap_or_default());
    assert_eq!(
        b.sha256,
        sha256_file(&out.join("b.mcap")).expect("b recording")
    );

    // Shards partition the runs deterministically; merge joins them.
    let s0 = campaign::run(&file, Some(1), Some((0, 2)), None, &quiet).expect("shard 0");
    let s1 = campaign::run(&file, Some(1), Some((1, 2)), None, &quiet).expect("shard 1");
    let names = |m: &campaign::Manifest| m.runs.iter().map(|r| r.name.clone()).collect::<Vec<_>>();
    assert_eq!(names(&s0), ["a", "c"]);
    assert_eq!(names(&s1), ["b"]);
    let merged = campaign::merge_manifests(&out).expect("merge");
    assert_eq!(names(&merged), ["a", "b", "c"]);
}

#[test]
fn campaign_file_errors_name_the_run() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, "[[runs]]\nname = \"x\"\nflow_rate = 3.0\n").expect("write");
    let err = campaign::load(&path).expect_err("unknown key");
    let msg = err.to_string();
    assert!(
        msg.contains("bad.toml") && msg.contains("runs[0]") && msg.contains("flow_rate"),
        "{msg}"
    );
    std::fs::write(&path, "[[runs]]\nname = \"x\"\n[[runs]]\nname = \"x\"\n").expect("write");
    assert!(
        campaign::load(&path)
            .expect_err("duplicate")
            .to_string()
            .contains("unique")
    );
}

//! The cluster path for real: `examples/slurm_campaign.sh` submitted as a job array to a
//! private single-node Slurm (Debian's `slurm-wlm`, started by `tools/slurm-single-node.sh`
//! in a temporary directory), merged, and compared with the same campaign run locally.
//! Ignored (skipped, with the reason; `build.rs`) where Slurm is not installed or the
//! build does not run as root (slurmd starts the jobs); `.ci/run` installs Slurm where it
//! can.

use std::path::{Path, PathBuf};
use std::process::Command;

use tmrotor::campaign;
use tmrotor::record::read_recording;

mod common;
use common::SMALL_CAMPAIGN as CAMPAIGN;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Stops the private cluster however the test ends.
struct Cluster(PathBuf);

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new("bash")
            .arg(root().join("tools/slurm-single-node.sh"))
            .arg("stop")
            .arg(&self.0)
            .status();
    }
}

fn missing_slurm() -> Option<String> {
    let uid = Command::new("id").arg("-u").output().ok()?;
    if String::from_utf8_lossy(&uid.stdout).trim() != "0" {
        return Some("not running as root (slurmd starts the jobs)".into());
    }
    for b in ["munged", "slurmctld", "slurmd", "sbatch", "sinfo"] {
        let found = Command::new("sh")
            .args(["-c", &format!("command -v {b}")])
            .output()
            .is_ok_and(|o| o.status.success());
        if !found {
            return Some(format!("{b} not found (Debian: apt-get install slurm-wlm)"));
        }
    }
    None
}

fn write_campaign(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).expect("dir");
    let file = dir.join("c.toml");
    std::fs::write(&file, CAMPAIGN).expect("campaign");
    file
}

#[test]
#[cfg_attr(
    not(tmrotor_slurm),
    ignore = "needs root and Slurm (Debian: apt-get install slurm-wlm; .ci/run installs it)"
)]
fn slurm_job_array_merges_to_the_local_campaign() {
    if let Some(why) = missing_slurm() {
        eprintln!("skipped: {why}");
        return;
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let cluster_dir = tmp.path().join("slurm");
    let _cluster = Cluster(cluster_dir.clone());
    let start = Command::new("bash")
        .arg(root().join("tools/slurm-single-node.sh"))
        .arg("start")
        .arg(&cluster_dir)
        .output()
        .expect("start script");
    assert!(
        start.status.success(),
        "the private Slurm did not start:\n{}\n{}",
        String::from_utf8_lossy(&start.stdout),
        String::from_utf8_lossy(&start.stderr)
    );
    let conf = cluster_dir.join("slurm.conf");

    // The job array: two shards of three runs, tmrotor from this build on the PATH.
    let jobs = tmp.path().join("cluster");
    let file = write_campaign(&jobs);
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_tmrotor"))
        .parent()
        .expect("bin dir")
        .to_path_buf();
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let submit = Command::new("sbatch")
        .env("SLURM_CONF", &conf)
        .env("PATH", &path)
        .arg("--wait")
        .arg("--array=0-1")
        .arg(format!("--chdir={}", jobs.display()))
        .arg(format!("--output={}/slurm-%A_%a.out", jobs.display()))
        .arg(root().join("examples/slurm_campaign.sh"))
        .arg(&file)
        .arg("2")
        .output()
        .expect("sbatch");
    let logs: String = std::fs::read_dir(&jobs)
        .expect("jobs dir")
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().starts_with("slurm-"))
        .map(|e| std::fs::read_to_string(e.path()).unwrap_or_default())
        .collect();
    assert!(
        submit.status.success(),
        "sbatch --wait failed:\n{}\n{}\njob logs:\n{logs}",
        String::from_utf8_lossy(&submit.stdout),
        String::from_utf8_lossy(&submit.stderr)
    );
    let out = jobs.join("out");
    assert!(out.join("manifest-shard-0-of-2.toml").exists(), "{logs}");
    assert!(out.join("manifest-shard-1-of-2.toml").exists(), "{logs}");
    let merged = campaign::merge_manifests(&out).expect("merge");

    // The same campaign, locally.
    let local_dir = tmp.path().join("local");
    let local_file = write_campaign(&local_dir);
    let quiet = |_: campaign::Event<'_>| {};
    let local = campaign::run(&local_file, Some(2), None, None, &quiet).expect("local");

    let names = |m: &campaign::Manifest| m.runs.iter().map(|r| r.name.clone()).collect::<Vec<_>>();
    assert_eq!(names(&merged), names(&local));
    for (c, l) in merged.runs.iter().zip(&local.runs) {
        assert_eq!(c.status, "completed", "{c:?}\n{logs}");
        assert_eq!((c.status.as_str(), c.points), (l.status.as_str(), l.points));
        assert_eq!(c.settings, l.settings, "run {}", c.name);
        let a = read_recording(out.join(&c.recording)).expect("cluster recording");
        let b = read_recording(local_dir.join("out").join(&l.recording)).expect("local");
        assert!(a.complete && b.complete);
        assert_eq!(a.points, b.points, "run {}: the points differ", c.name);
        assert_eq!(a.run.settings_toml, b.run.settings_toml);
    }
}

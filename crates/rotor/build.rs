//! Generates the protobuf message types of the recording layer from `proto/` with
//! protox (a pure-Rust protobuf compiler, so no system `protoc` is needed) and
//! prost-build. The generated code lands in `OUT_DIR` and is included by
//! `src/record/pb.rs`. The compiled descriptor sets embedded in recordings live in the
//! repository's `schemas/` and are checked against `proto/` by `tests/record_schemas.rs`.

use std::path::{Path, PathBuf};

fn proto_files(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut entries: Vec<_> = std::fs::read_dir(dir)?.collect::<Result<_, _>>()?;
    entries.sort_by_key(|e| e.path());
    for entry in entries {
        let path = entry.path();
        if path.is_dir() {
            proto_files(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "proto") {
            out.push(path);
        }
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let proto = Path::new("../../proto");
    println!("cargo:rerun-if-changed=../../proto");
    let mut files = Vec::new();
    proto_files(proto, &mut files)?;
    let fds = protox::compile(&files, [proto])?;
    prost_build::Config::new().compile_fds(fds)?;
    Ok(())
}

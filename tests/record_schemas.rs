//! `schemas/` must be exactly what `proto/` compiles to. Regenerate with
//! `tools/regen-schemas.sh` (which runs this test with `TMROTOR_WRITE_SCHEMAS=1`).

use std::path::Path;

use prost_reflect::DescriptorPool;
use tmrotor::record::schema::{ALL_SCHEMAS, ALL_TOPICS, MAP_TOPICS, TRANSIENT_TOPICS};

fn compile(proto_file: &str) -> Vec<u8> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut compiler = protox::Compiler::new([root.join("proto")]).expect("include path");
    compiler
        .include_imports(true)
        .include_source_info(false)
        .open_file(proto_file)
        .unwrap_or_else(|e| panic!("compiling {proto_file}: {e}"));
    compiler.encode_file_descriptor_set()
}

#[test]
fn schemas_dir_matches_proto_sources() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let write = std::env::var_os("TMROTOR_WRITE_SCHEMAS").is_some();
    let mut stale = Vec::new();
    for entry in ALL_SCHEMAS {
        let fresh = compile(entry.proto_file);
        let path = root.join("schemas").join(format!("{}.binpb", entry.name));
        if write {
            std::fs::write(&path, &fresh).expect("write schema");
            continue;
        }
        let on_disk = std::fs::read(&path).unwrap_or_default();
        if on_disk != fresh || entry.descriptor_set != fresh.as_slice() {
            stale.push(entry.name);
        }
    }
    assert!(
        stale.is_empty(),
        "schemas/ is stale for {stale:?}: run tools/regen-schemas.sh"
    );
    // No leftovers from removed messages.
    for file in std::fs::read_dir(root.join("schemas")).expect("schemas dir") {
        let name = file
            .expect("entry")
            .file_name()
            .to_string_lossy()
            .into_owned();
        if let Some(stem) = name.strip_suffix(".binpb") {
            assert!(
                ALL_SCHEMAS.iter().any(|s| s.name == stem),
                "schemas/{name} belongs to no message"
            );
        }
    }
}

#[test]
fn every_descriptor_set_is_self_contained_and_defines_its_message() {
    for entry in ALL_SCHEMAS {
        let pool = DescriptorPool::decode(entry.descriptor_set)
            .unwrap_or_else(|e| panic!("{}: descriptor set does not resolve: {e}", entry.name));
        assert!(
            pool.get_message_by_name(entry.name).is_some(),
            "{} not defined in its descriptor set",
            entry.name
        );
    }
}

#[test]
fn schemas_readme_lists_every_topic() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("schemas/README.md")).expect("README");
    for t in ALL_TOPICS
        .iter()
        .chain(&MAP_TOPICS)
        .chain(&TRANSIENT_TOPICS)
    {
        assert!(
            readme.contains(&format!("`{}`", t.name)) && readme.contains(t.schema.name),
            "schemas/README.md does not document topic {} ({})",
            t.name,
            t.schema.name
        );
    }
}

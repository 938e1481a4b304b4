#!/usr/bin/env bash
# Recompiles proto/ into the descriptor sets under schemas/ (one FileDescriptorSet with
# imports per published message, named <fully.qualified.Name>.binpb). No system protoc:
# the compilation uses protox through the schema test, which then checks the result.
set -euo pipefail
cd "$(dirname "$0")/.."
TMROTOR_WRITE_SCHEMAS=1 cargo test --release --test record_schemas schemas_dir_matches_proto_sources
cargo test --release --test record_schemas

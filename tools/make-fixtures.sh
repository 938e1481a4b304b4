#!/usr/bin/env bash
# Regenerates the committed recording fixtures under tests/fixtures/ from the synthetic
# closed-form run (tmrotor::record::synthetic). tests/record_fixture.rs reads them back and
# compares them with the closed form, so that recordings written by earlier builds stay
# readable. Only regenerate after a deliberate, versioned schema change.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --bin replay
target/release/replay synthetic tests/fixtures/synthetic_v1.mcap --points 6
target/release/replay synthetic tests/fixtures/synthetic_mech_v1.mcap --points 4 --mechanical

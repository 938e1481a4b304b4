#!/usr/bin/env bash
# The fixed workloads speed is judged on, each timed as a user runs it (wall and CPU
# seconds, the command's own summary line). One command per workload:
#
#   bash benches/workloads.sh W2          # one workload
#   bash benches/workloads.sh all         # W1 … W7 (about 12 minutes on a 2-core VM)
#   TMROTOR=/path/to/other/tmrotor bash benches/workloads.sh W1   # another build, side by side
#
# W1 built-in default sweep · W2 literature-value default sweep · W3 paper campaign ·
# W4 order 7 (built-in and literature values) · W5 switched period-doubled branches ·
# W6 the unilateral-contact benchmark · W7 the operating map. Outputs go to a temporary
# directory that is removed afterwards; docs/performance.md holds the figures measured.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${TMROTOR:-target/release/tmrotor}"
if [ ! -x "$bin" ]; then
  cargo build --release --bins
fi
bin="$(realpath "$bin")"
root="$PWD"
lit="$root/models/dual_rotor_literature.toml"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"

timed() { # NAME COMMAND...: runs it, prints its last summary lines and the time
  local name="$1"; shift
  local t0; t0=$(date +%s.%N)
  /usr/bin/time -f "%U %S" -o "$work/time" "$@" > "$work/out" 2>&1 || { cat "$work/out"; exit 1; }
  local t1; t1=$(date +%s.%N)
  read -r user sys < "$work/time"
  # the command's closing summary (a campaign's last progress line is its total)
  grep -E "points in|campaign:|time:|branches|saddle-nodes|guard|wrote" "$work/out" | tail -3 | sed 's/^/  /' || true
  awk -v n="$name" -v a="$t0" -v b="$t1" -v u="$user" -v s="$sys" \
    'BEGIN { printf "%s: %.1f s wall, %.1f s CPU\n", n, b - a, u + s }'
}

w1() { timed W1 "$bin" sweep -o w1.mcap; }
w2() { timed W2 "$bin" sweep --model "$lit" -o w2.mcap; }
w3() { sed 's|^output_dir = .*|output_dir = "w3-out"|' "$root/examples/paper_campaign.toml" > w3.toml
       timed W3 "$bin" campaign w3.toml --no-figures; }
w4() { timed W4-built-in "$bin" sweep --order 7 -o w4a.mcap
       timed W4-literature "$bin" sweep --order 7 --model "$lit" -o w4b.mcap; }
w5() { timed W5 "$bin" sweep --model "$lit" --flow 2 --cooling-temp 50 --no-half-orders -o w5.mcap; }
w6() { (cd "$root" && timed W6 cargo run --release -q --example contact); }
w7() { sed 's|^output_dir = .*|output_dir = "w7-out"|' "$root/examples/paper_map.toml" > w7.toml
       timed W7 "$bin" campaign w7.toml --no-figures
       timed W7-map "$bin" campaign map w7-out; }

case "${1:-all}" in
  W1|w1) w1 ;; W2|w2) w2 ;; W3|w3) w3 ;; W4|w4) w4 ;; W5|w5) w5 ;; W6|w6) w6 ;; W7|w7) w7 ;;
  all) w1; w2; w3; w4; w5; w6; w7 ;;
  *) echo "usage: bash benches/workloads.sh W1|W2|W3|W4|W5|W6|W7|all" >&2; exit 2 ;;
esac

#!/usr/bin/env bash
# Split a campaign over a Slurm job array: each array task runs one deterministic shard.
#
#   tmrotor campaign examples/paper_campaign.toml --dry-run --shard 0/6   # what task 0 runs
#   sbatch --array=0-5 examples/slurm_campaign.sh examples/paper_campaign.toml 6
#   # when all tasks are done:
#   tmrotor campaign merge examples/paper_campaign-out
#
# A task that reaches its time limit gets SIGTERM from Slurm: the run in progress stops after
# its current step with a complete recording (status `interrupted`), the manifest is
# written, and tmrotor exits with status 130, so the task shows as not completed.
# Submitting the same array again resumes: completed runs are skipped.
#
# The task's log (slurm-JOB_TASK.out) gets plain progress lines, not bars: one for each run
# that ends or is skipped as complete, and one on the shard every 15 s (`--quiet`: none).
#
# tmrotor must be on the compute nodes' PATH (`cargo install --path .`), built for their CPU:
# the default build targets x86-64-v3 (AVX2, FMA; see .cargo/config.toml), so on older nodes
# build with RUSTFLAGS="-C target-cpu=x86-64".
#
#SBATCH --job-name=tmrotor-campaign
#SBATCH --cpus-per-task=2
#SBATCH --time=01:00:00
set -euo pipefail
campaign=${1:?campaign file}
shards=${2:?number of shards}
tmrotor campaign "$campaign" --shard "${SLURM_ARRAY_TASK_ID}/${shards}" --threads "${SLURM_CPUS_PER_TASK:-1}"

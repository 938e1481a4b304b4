#!/usr/bin/env bash
# Split a campaign over a Slurm job array: each array task runs one deterministic shard.
#
#   sbatch --array=0-5 examples/slurm_campaign.sh examples/paper_campaign.toml 6
#   # when all tasks are done:
#   tmrotor campaign merge examples/paper_campaign-out
#
#SBATCH --job-name=tmrotor-campaign
#SBATCH --cpus-per-task=2
#SBATCH --time=01:00:00
set -euo pipefail
campaign=${1:?campaign file}
shards=${2:?number of shards}
tmrotor campaign "$campaign" --shard "${SLURM_ARRAY_TASK_ID}/${shards}" --threads "${SLURM_CPUS_PER_TASK:-1}" --quiet

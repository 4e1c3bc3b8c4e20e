#!/usr/bin/env bash
# Install, build and run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
# For the Slurm test (tests/slurm_test.sh), which starts daemons of its own: Debian's Slurm and munge;
# for the older-CPU test (tests/older_cpu_test.sh): QEMU's user-mode emulator; for the report's test
# (tests/cli/report_test.py): a headless browser; for the hostile-input suite (tests/cli/hostile_test.py):
# pytest.
scripts/setup.sh slurmctld slurmd slurm-client munge qemu-user chromium python3-pytest
scripts/build.sh
ctest --test-dir build --output-on-failure -j "$(nproc)" --timeout 900

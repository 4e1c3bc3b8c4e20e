#!/usr/bin/env bash
# Lucent on CPUs older than this one, as their programs see them: under QEMU's user-mode emulator
# (Debian's qemu-user) with the CPU model's CPUID, so that Embree, the lane clones and the C library
# choose their code for that CPU, and an instruction it lacks stops the process (SIGILL). Per model:
# the visibility tests (Embree packets on every ISA the model runs), a render whose reported ISAs
# are the model's and whose image matches a native render at that ISA, and on the AVX2 model (the
# common cluster node without AVX-512) the ISA tests, which render every method with the lane loops
# and Embree kernels that model picks (where this CPU has AVX-512; without it the main tests ran
# them natively with the same picks). Not emulated: the comparison of Embree's kernels with one
# another (every ISA this CPU runs, natively, in the main tests: the same kernels, 73 s emulated).
# Skipped (exit 77, with the reason) where qemu-x86_64 is missing.
#   tests/older_cpu_test.sh LUCENT LUCENT_TESTS SOURCE_DIR
set -euo pipefail
lucent=$1 tests=$2 source=$3
if ! command -v qemu-x86_64 > /dev/null; then
  echo "SKIPPED: qemu-x86_64 not found (Debian's qemu-user; scripts/test.sh installs it)"
  exit 77
fi
work=$(mktemp -d /tmp/lucent-older-cpu-XXXXXX)
trap 'rm -rf "$work"' EXIT

# QEMU warns about CPUID bits its emulator leaves out (pcid, x2apic): noise, not findings.
emulate() {
  local cpu=$1
  shift
  qemu-x86_64 -cpu "$cpu" "$@" 2> >(grep -v "TCG doesn't support requested feature" >&2)
}

render=("$source/scenes/cornell-box.json" --spp 4 --resolution 48x40 --threads 2 --quiet)
for entry in Nehalem-v2:sse4.2:baseline SandyBridge-v2:avx:baseline Haswell-v4:avx2:avx2; do
  IFS=: read -r cpu isa lanes <<< "$entry"
  echo "== $cpu (Embree $isa, lanes $lanes)"
  emulate "$cpu" "$tests" "[visibility]"
  stats=$(emulate "$cpu" "$lucent" render "${render[@]}" -o "$work/emulated-$isa.exr")
  "$lucent" render "${render[@]}" --isa "$isa" -o "$work/native-$isa.exr" > /dev/null
  python3 - "$isa" "$lanes" "$stats" << 'PY'
import json, sys
isa, lanes, stats = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
if (stats["embree_isa"], stats["lane_isa"]) != (isa, lanes):
    sys.exit(f"the render chose Embree {stats['embree_isa']} and lanes {stats['lane_isa']}, not {isa} and {lanes}")
PY
  # Not bit for bit: the emulator computes Embree's reciprocal estimates (rcpps) exactly where the
  # hardware approximates them, which moves hit distances in their last bits. 1e-9 is far below the
  # noise of this render (relMSE 2.8 between two seeds).
  "$lucent" compare "$work/emulated-$isa.exr" "$work/native-$isa.exr" --metric relmse --max-error 1e-9 > /dev/null ||
    { echo "the render on $cpu differs from the native render with --isa $isa"; exit 1; }
done
# On a CPU without AVX-512 the main tests have run these natively with the kernels and lane loops
# the AVX2 model picks: emulated, they would only repeat them (37 s of CPU).
if grep -qw avx512f /proc/cpuinfo; then
  echo "== Haswell-v4: every method with the lane loops and Embree kernels it picks"
  emulate Haswell-v4 "$tests" "[isa]~Every instruction set's Embree kernels render every method's image alike"
else
  echo "== Haswell-v4: every method's [isa] tests ran natively (this CPU has AVX2 and no AVX-512, the model's choice)"
fi

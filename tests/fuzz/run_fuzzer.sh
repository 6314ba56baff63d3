#!/bin/sh
# Runs one libFuzzer harness for SECONDS from its seed corpus and fails on a
# finding in Lodestone's code.
#   tests/fuzz/run_fuzzer.sh BUILD_DIR HARNESS SECONDS
# HARNESS is scene, checkpoint, vdb_field or vdb_points. The scene and
# checkpoint harnesses stop at the first crash (any crash fails). The VDB
# harnesses run in fork mode and keep going after crashes, because OpenVDB 10
# itself is not hardened against corrupted files (heap overflows in
# io/Compression.h readCompressedValues, leaks in readTopology); each crash
# input is then replayed and its first stack frame outside the sanitizer
# runtime, libc and libstdc++ decides: inside OpenVDB it is reported as
# upstream, anywhere else it fails the run. Prints executions and crashes.
set -u
build=$1 h=$2 seconds=$3
bin="$build/tests/fuzz/fuzz_$h"
corpus="$build/corpus/$h" findings="$build/findings"
mkdir -p "$corpus" "$findings"
log="$findings/$h.log"
export UBSAN_OPTIONS=print_stacktrace=1
case $h in
  vdb_*) mode="-fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1" ;;
  *) mode="" ;;
esac
# shellcheck disable=SC2086
"$bin" -max_total_time="$seconds" -rss_limit_mb=8192 -timeout=20 -print_final_stats=1 $mode \
  -artifact_prefix="$findings/$h-" "$corpus" "tests/fuzz/corpus/$h" >"$log" 2>&1
rc=$?
execs=$(grep -E "stat::number_of_executed_units|^#[0-9]+:|DONE" "$log" | tail -1)
echo "fuzz_$h: rc $rc; $execs"
ours=0 upstream=0
for a in "$findings/$h"-crash-* "$findings/$h"-leak-* "$findings/$h"-oom-*; do
  [ -e "$a" ] || continue
  frame=$("$bin" "$a" 2>&1 | grep -E '^ +#[0-9]+ ' |
    grep -vE 'interceptor|__asan|__sanitizer|__ubsan| in malloc| in calloc| in realloc|operator new|operator delete|libc\.so|libstdc\+\+|fuzzer::|bounded_new\.h|abort|raise|pthread_kill|__assert_fail|<unknown module>' |
    head -1)
  case $frame in
    *openvdb*) upstream=$((upstream + 1)); echo "  upstream (OpenVDB): $(basename "$a"): $frame" ;;
    *) ours=$((ours + 1)); echo "  FINDING: $(basename "$a"): $frame" ;;
  esac
done
echo "fuzz_$h: $ours finding(s) in Lodestone, $upstream in OpenVDB"
if [ "$ours" -gt 0 ]; then exit 1; fi
case $h in vdb_*) exit 0 ;; esac
exit $rc

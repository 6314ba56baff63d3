# Sourced by the benchmark scripts: run_case DIR SCENE OUT LOG THREADS LABEL
# runs DIR/examples/lodestone on SCENE into OUT (output in LOG). Returns 0
# when it ran; 1, after printing LABEL and why, when the binary refused the
# scene (its memory estimate or a grid too large) or does not know one of
# its keys (an older binary); any other failure prints the log and exits.
run_case() {
  rm -rf "$3"
  if "$1/examples/lodestone" run "$2" --out "$3" --threads "$5" > "$4" 2>&1; then
    return 0
  fi
  if grep -q "unknown key" "$4"; then
    echo "$6: skipped: $(grep -o "unknown key '[^']*'" "$4" | head -1) (an older binary)"
    return 1
  fi
  if grep -q "needs about\|too large" "$4"; then
    echo "$6: refused: $(grep -o 'needs about.*\|too large.*' "$4" | head -1)"
    return 1
  fi
  cat "$4" >&2
  exit 1
}

#!/usr/bin/env bash
# `make bench`, part: MEXAX's two order and step-size controls ('hairer',
# 'deuflhard') side by side on the bar chains of 3 to 16 bars, TOL 1e-3 to
# 1e-9, both base methods, on the 8-bar anchor, and the accuracy's spread
# over the anchor's ten H0 on 8, 12 and 16 bars (flexmbs-bench-mexax-control;
# docs/solvers.md). Writes build/bench/mexax_control.txt and, with
# matplotlib, the work-precision plot build/bench/mexax_control.png (copy it
# to docs/ when the figures in docs/solvers.md are updated). Never asserts.
set -u
cd "$(dirname "$0")/.."
FPM=${FPM:-fpm}
BIN=$($FPM run --profile release --example flexmbs-bench-mexax-control --runner echo 2>/dev/null | tail -1)
if [ ! -x "$BIN" ]; then
    echo "bench: could not build flexmbs-bench-mexax-control" >&2
    exit 1
fi
OUT=build/bench
mkdir -p "$OUT"
OPENBLAS_NUM_THREADS=1 "$BIN" | tee "$OUT/mexax_control.txt"
PY=/usr/bin/python3; [ -x "$PY" ] || PY=python3  # matplotlib: the system's (python3-matplotlib)
"$PY" bench/mexax_control_plot.py "$OUT/mexax_control.txt" "$OUT/mexax_control.png" \
    || echo "bench: no plot (matplotlib missing?)"

#!/usr/bin/env bash
# Add up the `N passed, M failed` lines of every suite log given as argument,
# plus "FAIL compile/run" lines of drivers that died before summarising.
# Prints one line `N passed, M failed` last; exits non-zero when M > 0.
passed=0; failed=0
for log in "$@"; do
    [ -f "$log" ] || { failed=$((failed + 1)); echo "missing log $log"; continue; }
    while read -r p f; do
        passed=$((passed + p)); failed=$((failed + f))
    done < <(sed -nE 's/^[[:space:]]*([0-9]+) passed, ([0-9]+) failed[[:space:]]*$/\1 \2/p' "$log")
    n=$(grep -cE '^FAIL (compile|run) ' "$log")
    failed=$((failed + n))
    # A suite that exited non-zero without reporting any failure still failed.
    if grep -qE '^exit [1-9]' "$log" && ! grep -qE '^[[:space:]]*[0-9]+ passed, [1-9][0-9]* failed' "$log" \
        && [ "$n" -eq 0 ]; then
        failed=$((failed + 1)); echo "$log: exited non-zero without a failure count"
    fi
done
echo "${passed} passed, ${failed} failed"
[ "$failed" -eq 0 ]

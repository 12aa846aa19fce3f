# Shell functions the benchmark scripts share (sourced, not run): scene
# variants, runs with their CPU, steps and peak memory, best of several,
# fitted exponents. Needs BIN (the flexmbs executable) and a current folder
# at the project root.

# variant OUT SRC SOLVER LS [SEDEXPR [SYSTEM]]: scene SRC with solver SOLVER,
# linear_solver LS and newton_system SYSTEM (default: the scene's), the sed
# edits SEDEXPR, its mesh file named from SRC's folder; into OUT
variant() {
    local system=""
    [ -n "${6:-}" ] && system="\n    newton_system = '$6'"
    sed -e "s/^    name = 'radau5'/    name = '$3'\n    linear_solver = '$4'$system/" \
        -e "${5:-}" -e "s#mesh_file = '\([^/']\)#mesh_file = '$PWD/$(dirname "$2")/\1#" \
        "$2" > "$1"
    grep -q "linear_solver = '$4'" "$1" ||
        sed -i "s/^&solver/\&solver\n    name = '$3'\n    linear_solver = '$4'$system/" "$1"
}

# in_scene_folder SCENE COMMAND...: COMMAND run from SCENE's folder, where a
# scene without &output file writes its result (the working folder), not
# the repository's top
in_scene_folder() {
    local scene=$1
    shift
    (cd "$(dirname "$scene")" && "$@")
}

# run FILE -> "CPU NST PEAK_KB NFE LU" (CPU, NST and NFE from the statistics
# line, LU the factorisation named by the line after it: klu, mumps, dense, ...)
run() {
    local line peak=-
    if [ -n "${TIME:-}" ]; then
        line=$(in_scene_folder "$1" "$TIME" -f "PEAK %M" "$(realpath "$BIN")" run \
            "$(basename "$1")" --quiet 2>&1)
        peak=$(echo "$line" | sed -n 's/^PEAK //p')
    else
        line=$(in_scene_folder "$1" "$(realpath "$BIN")" run "$(basename "$1")" --quiet 2>&1)
    fi
    local stats
    stats=$(echo "$line" | grep -E '^[a-z0-9]+: NST=' | tail -1)
    [ -n "$stats" ] || { echo "failed - - - -"; return; }
    local lu
    lu=$(echo "$line" | sed -n 's/^linear solver: \(condensed \)\{0,1\}\([a-z]*\).*/\2/p' | tail -1)
    echo "$(echo "$stats" | sed 's/.*CPU=\([0-9.]*\).*/\1/') \
$(echo "$stats" | sed 's/.*NST=\([0-9]*\).*/\1/') $peak \
$(echo "$stats" | sed 's/.* NFE=\([0-9]*\).*/\1/') ${lu:--}"
}

best_cpu() {  # FILE REPS -> the run with the least CPU ("CPU NST PEAK NFE")
    local best="" r
    for _ in $(seq "$2"); do
        r=$(run "$1")
        if [ -z "$best" ] || awk -v a="${r%% *}" -v b="${best%% *}" 'BEGIN{exit !(a<b)}'; then
            best=$r
        fi
    done
    echo "$best"
}

# least-squares slope of log(y) on log(x) from lines "x y"
slope() {
    awk '$2 > 0 { lx = log($1); ly = log($2); n++; sx += lx; sy += ly; sxx += lx*lx; sxy += lx*ly }
         END { if (n < 2) print "-"; else printf "%.2f", (n*sxy - sx*sy) / (n*sxx - sx*sx) }'
}

ratio() {  # A B -> A / B with two decimals ("-" when B is not positive)
    awk -v a="$1" -v b="$2" 'BEGIN { if (b + 0 > 0 && a + 0 > 0) printf "%.2f", a / b; else print "-" }'
}

#!/usr/bin/env bash
# The fuzz campaign behind `./dev fuzz`: every libFuzzer target of BUILD (or the ones named) for SECONDS
# CPU seconds each, on all cores (-fork=N for SECONDS/N wall seconds; on a busy machine a target runs
# again from its working corpus until its processes have used SECONDS of CPU, measured), with its dictionary
# (tests/fuzz/dict/), a working corpus seeded from tests/fuzz/corpus/<target>, artifacts under OUT.
# Prints a table (target, CPU seconds used, executions, cov and ft from libFuzzer's last stats line,
# findings); each
# finding is minimized (-minimize_crash=1) and printed with the tetpack command that reproduces it.
#   campaign.sh BUILD OUT SECONDS [TARGET...]
set -uo pipefail
build=$1 out=$2 budget=$3
shift 3
src=$(cd "$(dirname "$0")/../../.." && pwd)
fuzz_dir=$src/tests/fuzz
jobs=$(nproc 2>/dev/null || echo 2)
wall=$(((budget + jobs - 1) / jobs))
build=$(cd "$build" && pwd)
mkdir -p "$out"/{corpus,artifacts,logs,repro}
out=$(cd "$out" && pwd)

targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    for exe in "$build"/tests/fuzz/fuzz_*; do
        name=$(basename "$exe")
        [[ -x $exe && $name != *_replay ]] && targets+=("$name")
    done
fi

# The dictionary of a target: its format's, or every one for check (it reads them all).
dict_for() {
    case $1 in
        fuzz_vtk) echo vtk ;;
        fuzz_vtu | fuzz_pvd) echo vtu ;;
        fuzz_gmsh | fuzz_gzip) echo gmsh ;;
        fuzz_inp) echo inp ;;
        fuzz_xdmf) echo xdmf ;;
        fuzz_dolfin) echo dolfin ;;
        fuzz_medit) echo medit ;;
        fuzz_tetgen) echo tetgen ;;
        fuzz_openfoam) echo openfoam ;;
        fuzz_scene | fuzz_render_scene | fuzz_extract_scene) echo scene ;;
        fuzz_reader | fuzz_tpk | fuzz_tpk_struct | fuzz_partset) echo tpk ;;
        fuzz_stl | fuzz_off | fuzz_ply | fuzz_csv | fuzz_surface) echo surface ;;
        fuzz_check) echo all ;;
    esac
}
grep -hv '^#' "$fuzz_dir"/dict/*.dict | sort -u > "$out/all.dict"

# A .tpk for the scene findings of fuzz_scene (the other scene targets keep their own fixture).
tetpack=$build/tetpack
[ -f "$out/cylinder.tpk" ] || "$tetpack" convert "$src/samples/cylinder.vtk" "$out/cylinder.tpk" --quiet || true

# repro TARGET ARTIFACT: the files of a finding under OUT/repro and the tetpack command reading them.
repro() {
    local target=$1 artifact=$2 keep
    keep=$out/repro/$target-$(basename "$artifact")
    rm -rf "$keep" && mkdir -p "$keep"
    case $target in
        fuzz_reader | fuzz_tpk | fuzz_tpk_struct)
            cp "$artifact" "$keep/input.tpk"
            echo "$tetpack check $keep/input.tpk" ;;
        fuzz_gzip)
            cp "$artifact" "$keep/input.msh.gz"
            echo "$tetpack check $keep/input.msh.gz" ;;
        fuzz_surface)
            cp "$artifact" "$keep/input"
            echo "$tetpack check --format surface $keep/input" ;;
        fuzz_scene)
            cp "$artifact" "$keep/scene.json"
            echo "$tetpack render $out/cylinder.tpk -o $keep/x.png --backend cpu --scene $keep/scene.json" ;;
        *) # the target writes the files it reads into TPK_FUZZ_KEEP (tests/fuzz/support.h)
            TPK_FUZZ_KEEP=$keep timeout 120 "$build/tests/fuzz/$target" "$artifact" > /dev/null 2>&1
            case $target in
                fuzz_openfoam) echo "$tetpack check $keep/work/case" ;;
                fuzz_pvd) echo "$tetpack check $keep/work/series/series.pvd" ;;
                fuzz_partset) echo "$tetpack info $keep/work/set/set.tpkset" ;;
                fuzz_render_scene)
                    echo "$tetpack render $keep/fixture.tpk -o $keep/x.png --scene $keep/work/scene.json --backend cpu --size 16x12 --threads 1" ;;
                fuzz_extract_scene)
                    echo "$tetpack extract $keep/fixture.tpk $keep/x.tpk --scene $keep/work/scene.json --threads 1" ;;
                *) # fuzz_check and the importers: one file under work/; check reads fields leniently, convert strictly
                    local file
                    file=$(find "$keep/work" -maxdepth 1 -type f -print -quit 2>/dev/null)
                    echo "$tetpack check $file; $tetpack convert $file $keep/x.tpk" ;;
            esac ;;
    esac
}

# CPU seconds (user + system) this shell's waited-for children have used so far, into $cpu: `times` run in
# this shell (in a $(...) subshell it would count the subshell's children only).
children_cpu() {
    times > "$out/logs/.times"
    cpu=$(tail -1 "$out/logs/.times" | awk '{ s = 0; for (i = 1; i <= 2; i++) { split($i, a, "m"); sub("s", "", a[2]); s += a[1] * 60 + a[2] } printf "%d", s }')
}

table=$out/table.txt
printf '%-20s %7s %12s %8s %8s %9s\n' target cpu_s executions cov ft findings | tee "$table"
for target in "${targets[@]}"; do
    exe=$build/tests/fuzz/$target
    seeds=$fuzz_dir/corpus/$target
    corpus=$out/corpus/$target
    artifacts=$out/artifacts/$target
    mkdir -p "$corpus" "$artifacts"
    dict=$(dict_for "$target")
    dict_arg=()
    if [ "$dict" = all ]; then dict_arg=(-dict="$out/all.dict"); elif [ -n "$dict" ]; then dict_arg=(-dict="$fuzz_dir/dict/$dict.dict"); fi
    log=$out/logs/$target.log
    : > "$log"
    children_cpu
    cpu_start=$cpu used=0 execs=0 stats=
    while [ "$used" -lt $((budget * 98 / 100)) ]; do
        left=$(((budget - used + jobs - 1) / jobs))
        [ "$left" -lt 10 ] && left=10
        # -ignore_*: keep fuzzing after a finding, so that every target gets its whole budget
        (cd "$out/logs" && "$exe" -fork="$jobs" -max_total_time="$left" -timeout=20 -rss_limit_mb=2560 -close_fd_mask=1 \
            -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 -artifact_prefix="$artifacts/" "${dict_arg[@]}" \
            "$corpus" "$seeds") > "$log.run" 2>&1
        cat "$log.run" >> "$log"
        run_stats=$(grep -E '^#[0-9]+: cov: ' "$log.run" | tail -1)
        [ -n "$run_stats" ] && stats=$run_stats && execs=$((execs + $(sed -E 's/^#([0-9]+):.*/\1/' <<< "$run_stats")))
        children_cpu
        used=$((cpu - cpu_start))
        [ -z "$run_stats" ] && break # it did not start: the log says why
    done
    rm -f "$log.run"
    cov=$(sed -E 's/.* cov: ([0-9]+).*/\1/' <<< "$stats")
    ft=$(sed -E 's/.* ft: ([0-9]+).*/\1/' <<< "$stats")
    findings=()
    for f in "$artifacts"/crash-* "$artifacts"/timeout-* "$artifacts"/oom-* "$artifacts"/leak-*; do
        [[ -f $f && $f != *.min ]] && findings+=("$f")
    done
    printf '%-20s %7s %12s %8s %8s %9s\n' "$target" "$used" "$execs" "${cov:--}" "${ft:--}" "${#findings[@]}" | tee -a "$table"
    for f in "${findings[@]}"; do
        [ -f "$f.min" ] || "$exe" -minimize_crash=1 -max_total_time=60 -timeout=20 -exact_artifact_path="$f.min" "$f" \
            > "$out/logs/$target.minimize.log" 2>&1
        [ -f "$f.min" ] || cp "$f" "$f.min"
        echo "  finding $(basename "$f") ($(stat -c %s "$f.min") bytes minimized: $f.min)" | tee -a "$table"
        echo "    reproduce: $(repro "$target" "$f.min")" | tee -a "$table"
    done
done
echo "fuzz: ${budget} CPU seconds per target (-fork=$jobs for ${wall}s a run), table in $table, logs in $out/logs"

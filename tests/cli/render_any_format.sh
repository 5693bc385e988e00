# tetpack render FILE for every input format of the registry (tetpack formats --json) that has a sample
# among the real meshes (../shared/data, listed in its MANIFEST.md) or the bundled test files: the mesh is
# converted in memory with convert's defaults, so the picture is byte-identical to rendering the .tpk
# that `tetpack convert` writes; --save-tpk keeps that same file; a file that is no mesh is refused
# with a message saying what to do.
source "$(dirname "$0")/common.sh"

"$TPK" formats --json > "$WORK/formats.json"
# One line per format: NAME and its samples, smallest first (a TetGen sample by its .node).
"$PY" - "$WORK/formats.json" "$DATA" "$SRC" > "$WORK/samples.txt" <<'PYEOF'
import json, os, sys
formats = json.load(open(sys.argv[1]))["formats"]
roots = [sys.argv[2], os.path.join(sys.argv[3], "samples"), os.path.join(sys.argv[3], "tests", "cli", "dolfin")]
files = []
for root in roots:
    for d, _, names in os.walk(root):
        files += [os.path.join(d, n) for n in names]
files.sort(key=lambda f: (os.path.getsize(f), f))
for f in formats:
    exts = [e for e in f["extensions"] if e != ".ele"]
    hits = [p for p in files if any(p.lower().endswith(e) for e in exts)]
    print(f["name"], *hits[:6])
PYEOF

rendered=()
while read -r name samples; do
    for sample in $samples; do
        tag=$name
        # a sample convert refuses with its defaults (a "hard" file that needs repair options) is not one
        "$TPK" convert "$sample" "$WORK/$tag.tpk" --quiet 2> /dev/null || continue
        "$TPK" render "$WORK/$tag.tpk" -o "$WORK/$tag-tpk.png" --size 48x40 --threads 2 > /dev/null \
            || fail "render of the converted $sample"
        "$TPK" render "$sample" -o "$WORK/$tag.png" --size 48x40 --threads 2 --save-tpk "$WORK/$tag-kept.tpk" \
            > /dev/null 2> "$WORK/err" || { cat "$WORK/err" >&2; fail "render $sample ($name)"; }
        cmp -s "$WORK/$tag.png" "$WORK/$tag-tpk.png" || fail "$name: render $sample differs from render of its convert"
        "$TPK" info "$WORK/$tag-kept.tpk" > /dev/null || fail "$name: --save-tpk wrote no readable .tpk"
        "$TPK" render "$sample" -o "$WORK/$tag-mem.png" --size 48x40 --threads 2 > /dev/null || fail "render $sample"
        cmp -s "$WORK/$tag.png" "$WORK/$tag-mem.png" || fail "$name: in memory and --save-tpk differ"
        rendered+=("$name")
        echo "render $name: $sample"
        break
    done
done < "$WORK/samples.txt"
# Every format with a sample in the corpus (MANIFEST.md) renders; a format that loses its sample fails here.
for want in vtk tetgen vtu gmsh medit ugrid exodus cgns meshb dolfin; do
    [[ " ${rendered[*]} " == *" $want "* ]] || fail "no sample of $want rendered (rendered: ${rendered[*]})"
done
# Nothing is left behind by the in-memory conversions.
[ -z "$(find "$WORK" -name '*.tpk.*' -o -name '.tetpack*')" ] || fail "temporary files left in $WORK"

# Not a mesh: refused (exit 2) with what render takes and what to do, and no image.
printf 'x,y\n1,2\n' > "$WORK/table.txt"
expect_exit 2 "$TPK" render "$WORK/table.txt" -o "$WORK/no.png"
expect_stderr "neither a .tpk nor a mesh in a format tetpack reads (its first bytes: 78 2c 79"
expect_stderr "render takes a .tpk or any input of \`tetpack formats\`"
[ ! -e "$WORK/no.png" ] || fail "an image was written for a file that is no mesh"
expect_exit 2 "$TPK" render "$WORK/missing.vtk" -o "$WORK/no.png"
expect_stderr "missing.vtk: cannot open it"
# --save-tpk with a .tpk input, or onto the input itself, is refused before any work
expect_exit 2 "$TPK" render "$WORK/vtk.tpk" -o "$WORK/no.png" --save-tpk "$WORK/again.tpk"
expect_stderr "is a .tpk already"
expect_exit 2 "$TPK" render "$SRC/samples/cylinder.vtk" -o "$WORK/no.png" --save-tpk "$SRC/samples/cylinder.vtk"
expect_stderr "--save-tpk"
echo "ok: ${rendered[*]}"

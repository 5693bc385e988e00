#!/usr/bin/env bash
# tetpack check on .tpk files: exit 0 for a clean file, 1 for a file that opens but breaks a rule of the
# spec (with the finding in --json), 2 for a file no reader can open (with a message naming it).
source "$(dirname "$0")/common.sh"

convert_checked "$SRC/samples/cylinder.vtk" "$WORK/c.tpk" --layout tet16 --layout tet32 --quiet
expect_exit 0 "$TPK" check "$WORK/c.tpk"
grep -q "no problems found" "$WORK/out" || fail "clean file: $(cat "$WORK/out")"
expect_exit 0 "$TPK" check "$WORK/c.tpk" --json
$PY - "$WORK/out" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
assert d["format"] == "tpk" and d["tets"] == 1348 and d["problems"] is False, d
assert "file" in [g["name"] for g in d["groups"]], d["groups"]
assert not [f for f in d["findings"] if f["id"] >= 600], d["findings"]
PY

# One byte of the TT16 chunk changed: the file opens, its checksum fails (rule 16): 600, exit 1.
offset=$("$TPK" info "$WORK/c.tpk" | awk '$2 == "TT16" {print $7}')
[ -n "$offset" ] || fail "no TT16 offset in tetpack info"
cp "$WORK/c.tpk" "$WORK/flip.tpk"
printf '\x55' | dd of="$WORK/flip.tpk" bs=1 seek=$((offset + 20)) conv=notrunc status=none
expect_exit 1 "$TPK" check "$WORK/flip.tpk"
grep -q "600 error   file_rule" "$WORK/out" || fail "no 600 line: $(cat "$WORK/out")"
# The header's counts are still reported (they were "0 vertices, 0 cells").
counts=$("$TPK" info "$WORK/c.tpk" --json | $PY -c 'import json,sys; d=json.load(sys.stdin); print(d["vertices"], d["tets"])')
grep -q "tpk, ${counts% *} vertices, ${counts#* } cells" "$WORK/out" || fail "no header counts ($counts): $(head -1 "$WORK/out")"
expect_exit 1 "$TPK" check "$WORK/flip.tpk" --json
$PY - "$WORK/out" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
f = {x["id"]: x for x in d["findings"]}
assert d["problems"] is True and list(f) == [600] and f[600]["count"] == 1, d["findings"]
assert "TPK-R16" in f[600]["examples"][0]["note"] and "'TT16'" in f[600]["examples"][0]["note"], f[600]
assert "not run" in f[600]["summary"], f[600]
PY
for opened in chunk_checksum zstd_skippable_frame zstd_chunk_checksum tet16_vx cull_block_count; do
    expect_exit 1 "$TPK" check "$SRC/samples/vectors/$opened.tpk"
    grep -q "^  600 " "$WORK/out" || fail "$opened.tpk: no check 600: $(cat "$WORK/out")"
done

# Files no reader can open: exit 2, the file named on stderr, nothing on stdout.
head -c 100 "$WORK/c.tpk" > "$WORK/short.tpk"
for bad in "$WORK/short.tpk" "$SRC/samples/vectors/bad_magic.tpk" "$SRC/samples/vectors/newer_major.tpk" \
           "$SRC/samples/vectors/overlap.tpk" "$SRC/samples/vectors/nonfinite_origin.tpk" \
           "$SRC/samples/vectors/empty_fdsc.tpk" "$SRC/samples/vectors/implausible_zstd_size.tpk" "$WORK/missing.tpk"; do
    expect_exit 2 "$TPK" check "$bad" --json
    expect_stderr "$(basename "$bad")"
    [ ! -s "$WORK/out" ] || fail "output for an unreadable file: $(cat "$WORK/out")"
done

# Part sets (spec §13.4): two_parts.tpkset checks clean; bad_link.tpkset's containers are valid but its
# links do not answer each other: check 614 for both links, exit 1.
expect_exit 0 "$TPK" check "$SRC/samples/vectors/two_parts.tpkset"
expect_exit 1 "$TPK" check "$SRC/samples/vectors/bad_link.tpkset" --json
$PY - "$WORK/out" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
f = {x["id"]: x for x in d["findings"]}
assert d["format"] == "tpkset" and list(f) == [614] and f[614]["count"] == 2, d["findings"]
assert f[614]["name"] == "tpk_s01_links" and "link the face back" in f[614]["examples"][0]["note"], f[614]
PY

# Culling blocks (spec §13.6): two_tets_cull.tpk checks clean; cull_bad_seed.tpk's CULL is within rule 17
# but its seed's n3 is not tet 0's neighbor opposite vertex 4: check 616 alone, exit 1.
expect_exit 0 "$TPK" check "$SRC/samples/vectors/two_tets_cull.tpk"
expect_exit 1 "$TPK" check "$SRC/samples/vectors/cull_bad_seed.tpk" --json
$PY - "$WORK/out" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
f = {x["id"]: x for x in d["findings"]}
assert d["format"] == "tpk" and list(f) == [616] and f[616]["count"] == 1, d["findings"]
ex = f[616]["examples"][0]
assert f[616]["name"] == "tpk_b01_blocks" and ex["kind"] == "block" and ex["ids"] == [0, 0, 0], f[616]
assert "n3 is 1" in ex["note"] and "is -1" in ex["note"], ex
PY

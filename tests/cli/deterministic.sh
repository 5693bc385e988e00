# Same input and options give byte-identical files, whatever the output name and thread count.
source "$(dirname "$0")/common.sh"
convert_checked "$DATA/sfepy/piezo_mesh_micro.vtk" "$WORK/a.tpk" --layout tet16 --layout tet32 --threads 1 --quiet
convert_checked "$DATA/sfepy/piezo_mesh_micro.vtk" "$WORK/b.tpk" --layout tet16 --layout tet32 --threads 2 --quiet
cmp "$WORK/a.tpk" "$WORK/b.tpk" || fail "outputs differ"
convert_checked "$DATA/sfepy/piezo_mesh_micro.vtk" "$WORK/z1.tpk" --zstd 5 --quiet
convert_checked "$DATA/sfepy/piezo_mesh_micro.vtk" "$WORK/z2.tpk" --zstd 5 --quiet
cmp "$WORK/z1.tpk" "$WORK/z2.tpk" || fail "zstd outputs differ"
echo "1 passed, 0 failed"

# Same input and options give byte-identical files, whatever the output name and thread count.
source "$(dirname "$0")/common.sh"
convert_checked "$DATA/sfepy/piezo_mesh_micro.vtk" "$WORK/a.tpk" --layout tet16 --layout tet32 --threads 1 --quiet
convert_checked "$DATA/sfepy/piezo_mesh_micro.vtk" "$WORK/b.tpk" --layout tet16 --layout tet32 --threads 2 --quiet
cmp "$WORK/a.tpk" "$WORK/b.tpk" || fail "outputs differ"
# With zstd chunks too (the records are built on worker threads, then compressed in pieces as they come):
# the bytes must not depend on how many threads.
convert_checked "$DATA/sfepy/piezo_mesh_micro.vtk" "$WORK/z1.tpk" --zstd 5 --layout tet16 --layout tet32 --threads 1 --quiet
for threads in 2 3 8; do
    convert_checked "$DATA/sfepy/piezo_mesh_micro.vtk" "$WORK/z$threads.tpk" --zstd 5 --layout tet16 --layout tet32 \
        --threads $threads --quiet
    cmp "$WORK/z1.tpk" "$WORK/z$threads.tpk" || fail "zstd outputs differ between 1 and $threads threads"
done
echo "1 passed, 0 failed"

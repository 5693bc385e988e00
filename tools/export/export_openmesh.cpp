// OpenMesh shim: the shell as an OpenMesh triangle mesh, written by OpenMesh's OBJ, OFF and STL writers
// into memory (the C side renames it into place atomically). C++17, behind export_openmesh.h.
#include "export_openmesh.h"

// OpenMesh's property arrays push_back default-constructed (uninitialized) Vec3d; GCC 12 sees that
// through std::vector's inlined allocator and warns in the system headers. Nothing reads them unset.
#if defined(__GNUC__) && !defined(__clang__) // clang has no such warning and refuses the unknown name
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct ShellTraits : OpenMesh::DefaultTraits {
    typedef OpenMesh::Vec3d Point; // world coordinates need doubles (meshes far from the origin)
    typedef OpenMesh::Vec3d Normal;
};
typedef OpenMesh::TriMesh_ArrayKernelT<ShellTraits> ShellMesh;

// A halfedge mesh cannot hold a non-manifold vertex or edge; add_face refuses such a face. It is added
// again on fresh copies of its corners (same positions), so no face is lost; the caller says how many.
int64_t build(ShellMesh &mesh, const double *xyz, int64_t vertex_count, const int32_t *tri, int64_t face_count)
{
    std::vector<ShellMesh::VertexHandle> vh((size_t)vertex_count);
    for (int64_t v = 0; v < vertex_count; v++)
        vh[(size_t)v] = mesh.add_vertex(ShellMesh::Point(xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]));
    int64_t split = 0;
    omerr().disable(); // add_face prints "complex edge/vertex" for what is counted and handled here
    for (int64_t f = 0; f < face_count; f++) {
        const int32_t *t = tri + 3 * f;
        if (mesh.add_face(vh[(size_t)t[0]], vh[(size_t)t[1]], vh[(size_t)t[2]]).is_valid())
            continue;
        ShellMesh::VertexHandle copy[3];
        for (int k = 0; k < 3; k++)
            copy[k] = mesh.add_vertex(mesh.point(vh[(size_t)t[k]]));
        mesh.add_face(copy[0], copy[1], copy[2]);
        split++;
    }
    omerr().enable();
    return split;
}

int fail(tpk_openmesh_result *result, const char *what)
{
    std::snprintf(result->error, sizeof result->error, "%s", what);
    return -1;
}

} // namespace

extern "C" int tpk_openmesh_write(const char *format, const double *xyz, int64_t vertex_count,
                                  const int32_t *tri, int64_t face_count, tpk_openmesh_result *result)
{
    std::memset(result, 0, sizeof *result);
    const std::string ext = std::string(".") + format;
    if (ext != ".obj" && ext != ".off" && ext != ".stl")
        return fail(result, "OpenMesh export: format must be obj, off or stl");
    try {
        ShellMesh mesh;
        result->split_faces = build(mesh, xyz, vertex_count, tri, face_count);
        OpenMesh::IO::Options options;
        if (ext == ".stl") { // STL stores a normal per face: the outward one, from our vertex order
            mesh.request_face_normals();
            mesh.update_face_normals();
            options += OpenMesh::IO::Options::Binary;
            options += OpenMesh::IO::Options::FaceNormal;
        }
        std::ostringstream out(std::ios::out | std::ios::binary);
        omlog().disable(); // the writers log "[OBJWriter] : write file" on stdout; our summary is enough
        bool written = OpenMesh::IO::write_mesh(mesh, out, ext, options, 17);
        omlog().enable();
        if (!written)
            return fail(result, "OpenMesh's writer failed");
        const std::string bytes = out.str();
        result->bytes = std::malloc(bytes.size() ? bytes.size() : 1);
        if (!result->bytes)
            return fail(result, "out of memory for the written file");
        std::memcpy(result->bytes, bytes.data(), bytes.size());
        result->size = bytes.size();
        return 0;
    } catch (const std::exception &e) {
        return fail(result, e.what());
    }
}

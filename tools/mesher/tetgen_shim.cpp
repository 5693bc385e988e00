// The only TetGen translation unit (tetgen_shim.h). In library mode (TETLIBRARY) TetGen reports errors
// by `throw` of an int (terminatetetgen in tetgen.h) and prints with printf even under -Q when it fails;
// both are caught here so the converter gets a message and stdout stays clean (e.g. for --json).
#define TETLIBRARY
#include <tetgen.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include <unistd.h>

#include "tetgen_shim.h"

namespace {

// Send file descriptor 1 to a temporary file (or to a copy of print_fd) while alive; text() returns
// what was printed.
class StdoutCapture {
public:
    explicit StdoutCapture(int print_fd)
    {
        std::fflush(stdout);
        file_ = print_fd < 0 ? std::tmpfile() : fdopen(dup(print_fd), "w+");
        saved_ = file_ ? dup(1) : -1;
        if (saved_ >= 0 && dup2(fileno(file_), 1) < 0) {
            close(saved_);
            saved_ = -1;
        }
    }
    ~StdoutCapture()
    {
        restore();
        if (file_)
            std::fclose(file_);
    }
    std::string text()
    {
        restore();
        std::string all;
        if (!file_)
            return all;
        std::rewind(file_);
        char buf[4096];
        size_t got;
        while ((got = std::fread(buf, 1, sizeof buf, file_)) > 0 && all.size() < 65536)
            all.append(buf, got);
        return all;
    }

private:
    void restore()
    {
        if (saved_ < 0)
            return;
        std::fflush(stdout);
        dup2(saved_, 1);
        close(saved_);
        saved_ = -1;
    }
    std::FILE *file_ = nullptr;
    int saved_ = -1;
};

const char *code_text(int code)
{
    switch (code) {
    case TPK_TETGEN_OUT_OF_MEMORY: return "TetGen ran out of memory";
    case TPK_TETGEN_INTERNAL_ERROR: return "TetGen hit an internal error";
    case TPK_TETGEN_SELF_INTERSECTION: return "TetGen found a self-intersection of the surface";
    case TPK_TETGEN_SMALL_FEATURE: return "TetGen found a very small input feature (below its tolerance)";
    case TPK_TETGEN_CLOSE_FACETS: return "TetGen found two very close input facets";
    case TPK_TETGEN_INPUT_ERROR: return "TetGen found an error in its input";
    default: return "TetGen failed";
    }
}

// The last few non-empty lines TetGen printed, joined by "; ".
std::string last_lines(const std::string &printed)
{
    std::vector<std::string> lines;
    size_t at = 0;
    while (at < printed.size()) {
        size_t nl = printed.find('\n', at);
        std::string line = printed.substr(at, nl == std::string::npos ? std::string::npos : nl - at);
        while (!line.empty() && (line.back() == ' ' || line.back() == '\r' || line.back() == '.'))
            line.pop_back();
        if (line.find_first_not_of(' ') != std::string::npos)
            lines.push_back(line.substr(line.find_first_not_of(' ')));
        at = nl == std::string::npos ? printed.size() : nl + 1;
    }
    std::string joined;
    for (size_t i = lines.size() > 4 ? lines.size() - 4 : 0; i < lines.size(); i++)
        joined += (joined.empty() ? "" : "; ") + lines[i];
    return joined;
}

// tetgenio frees its arrays with delete[]: everything handed to it is allocated with new[].
void fill_input(const tpk_tetgen_input *in, tetgenio &io)
{
    io.firstnumber = 0;
    io.numberofpoints = in->point_count;
    io.pointlist = new REAL[3 * static_cast<size_t>(in->point_count)];
    std::memcpy(io.pointlist, in->points, sizeof(double) * 3 * static_cast<size_t>(in->point_count));
    if (in->face_count == 0)
        return;
    io.numberoffacets = in->face_count;
    io.facetlist = new tetgenio::facet[in->face_count];
    for (int32_t f = 0; f < in->face_count; f++) {
        tetgenio::facet &facet = io.facetlist[f];
        tetgenio::init(&facet);
        facet.numberofpolygons = 1;
        facet.polygonlist = new tetgenio::polygon[1];
        tetgenio::init(&facet.polygonlist[0]);
        int64_t b = in->face_offsets[f], n = in->face_offsets[f + 1] - b;
        facet.polygonlist[0].numberofvertices = static_cast<int>(n);
        facet.polygonlist[0].vertexlist = new int[n];
        for (int64_t k = 0; k < n; k++)
            facet.polygonlist[0].vertexlist[k] = in->face_conn[b + k];
    }
}

template <typename T> T *copy_out(const T *src, size_t count)
{
    T *dst = static_cast<T *>(std::malloc(sizeof(T) * (count ? count : 1)));
    if (!dst)
        throw std::bad_alloc();
    if (count)
        std::memcpy(dst, src, sizeof(T) * count);
    return dst;
}

void take_output(const tetgenio &io, tpk_tetgen_output *out)
{
    out->point_count = io.numberofpoints;
    out->points = copy_out(io.pointlist, 3 * static_cast<size_t>(io.numberofpoints));
    out->tet_count = io.numberoftetrahedra;
    if (io.numberofcorners != 4 && io.numberoftetrahedra > 0)
        throw TPK_TETGEN_OTHER_ERROR;
    out->tets = copy_out(io.tetrahedronlist, 4 * static_cast<size_t>(io.numberoftetrahedra));
    out->triangle_count = io.numberoftrifaces;
    out->triangles = copy_out(io.trifacelist, 3 * static_cast<size_t>(io.numberoftrifaces));
}

} // namespace

extern "C" void tpk_tetgen_last_words(const char *printed, size_t size, char *buf, size_t cap)
{
    std::string said = last_lines(std::string(printed, size));
    if (cap)
        std::snprintf(buf, cap, "%s", said.c_str());
}

extern "C" int tpk_tetgen_run(const char *switches, const tpk_tetgen_input *in, tpk_tetgen_output *out,
                              char *message, size_t cap)
{
    return tpk_tetgen_run_printing_to(-1, switches, in, out, message, cap);
}

extern "C" int tpk_tetgen_run_printing_to(int print_fd, const char *switches, const tpk_tetgen_input *in,
                                          tpk_tetgen_output *out, char *message, size_t cap)
{
    std::memset(out, 0, sizeof *out);
    if (message && cap)
        message[0] = 0;
    std::vector<char> sw(switches, switches + std::strlen(switches) + 1);
    int code = 0;
    std::string printed;
    {
        StdoutCapture capture(print_fd);
        try {
            tetgenio input, output;
            fill_input(in, input);
            tetrahedralize(sw.data(), &input, &output);
            take_output(output, out);
        } catch (int thrown) {
            code = thrown == 0 ? TPK_TETGEN_OTHER_ERROR : thrown;
        } catch (const std::bad_alloc &) {
            code = TPK_TETGEN_OUT_OF_MEMORY;
        } catch (...) {
            code = TPK_TETGEN_OTHER_ERROR;
        }
        printed = capture.text();
    }
    if (code == 0)
        return 0;
    tpk_tetgen_output_free(out);
    std::string said = last_lines(printed);
    if (message && cap)
        std::snprintf(message, cap, "%s (code %d)%s%s", code_text(code), code, said.empty() ? "" : "; it said: ",
                      said.c_str());
    return code;
}

extern "C" void tpk_tetgen_output_free(tpk_tetgen_output *out)
{
    std::free(out->points);
    std::free(out->tets);
    std::free(out->triangles);
    std::memset(out, 0, sizeof *out);
}

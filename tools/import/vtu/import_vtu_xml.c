/* VTU importer, the XML side: expat's handlers walk VTKFile > UnstructuredGrid > Piece > Points, Cells,
 * PointData, CellData > DataArray and keep each DataArray (attributes checked, text collected, ascii and
 * binary contents decoded at its end tag). Raw appended data is split off before expat sees the file. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "import_vtu_internal.h"
#include "import/xml_input.h"
#include "base/text_scan.h"

static long cur_line(vtu_reader *r)
{
    return (long)XML_GetCurrentLineNumber(r->parser);
}

static const char *quote(const char *s, char *buf, size_t cap)
{
    return tpk_scan_quote(s, strlen(s), buf, cap);
}

static const char *attr(const XML_Char **atts, const char *key)
{
    for (int i = 0; atts[i]; i += 2)
        if (!strcmp(atts[i], key))
            return atts[i + 1];
    return NULL;
}

static int parse_count(const char *s, int64_t *out)
{
    size_t len = strlen(s);
    while (len && (s[len - 1] == ' ' || s[len - 1] == '\t' || s[len - 1] == '\n' || s[len - 1] == '\r'))
        len--;
    while (len && (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\r'))
        s++, len--;
    return tpk_parse_int64(s, len, out) != 0 || *out < 0 ? -1 : 0;
}

/* ---- DataArray collection ----------------------------------------------------------------------- */

static int keep_array(vtu_reader *r, vtu_array *a)
{
    if (r->array_count == r->array_cap) {
        int cap = r->array_cap ? 2 * r->array_cap : 8;
        vtu_array *grown = realloc(r->arrays, sizeof *grown * (size_t)cap);
        if (!grown)
            return vtu_fail_array(r, a, "out of memory");
        r->arrays = grown;
        r->array_cap = cap;
    }
    r->arrays[r->array_count++] = *a;
    a->values = NULL;
    return 0;
}

/* ---- XML handlers ------------------------------------------------------------------------------- */

static int start_vtkfile(vtu_reader *r, const XML_Char **atts)
{
    char q[64];
    const char *type = attr(atts, "type"), *order = attr(atts, "byte_order"), *header = attr(atts, "header_type"),
               *comp = attr(atts, "compressor");
    if (!type || strcmp(type, "UnstructuredGrid"))
        return vtu_fail_line(r, cur_line(r), "VTKFile: expected type=\"UnstructuredGrid\", found %s%s%s",
                             type ? "\"" : "", type ? quote(type, q, sizeof q) : "no type", type ? "\"" : "");
    if (order && !strcmp(order, "BigEndian"))
        r->big_endian = 1;
    else if (order && strcmp(order, "LittleEndian"))
        return vtu_fail_line(r, cur_line(r), "VTKFile: expected byte_order LittleEndian or BigEndian, found \"%s\"",
                             quote(order, q, sizeof q));
    if (header && !strcmp(header, "UInt64"))
        r->header_size = 8;
    else if (header && strcmp(header, "UInt32"))
        return vtu_fail_line(r, cur_line(r), "VTKFile: expected header_type UInt32 or UInt64, found \"%s\"",
                             quote(header, q, sizeof q));
    if (comp && !strcmp(comp, "vtkZLibDataCompressor"))
        r->compressed = 1;
    else if (comp && comp[0])
        return vtu_fail_line(r, cur_line(r), "VTKFile: expected compressor vtkZLibDataCompressor or none, found \"%s\" "
                             "(not supported)", quote(comp, q, sizeof q));
    return 0;
}

static int start_piece(vtu_reader *r, const XML_Char **atts)
{
    if (r->piece_seen)
        return vtu_fail_line(r, cur_line(r), "expected one Piece, found a second (multi-piece files are not read)");
    r->piece_seen = 1;
    const char *np = attr(atts, "NumberOfPoints"), *nc = attr(atts, "NumberOfCells");
    char q[64];
    if (!np || parse_count(np, &r->point_count))
        return vtu_fail_line(r, cur_line(r), "Piece: expected NumberOfPoints >= 0, found %s",
                             np ? quote(np, q, sizeof q) : "none");
    if (!nc || parse_count(nc, &r->cell_count))
        return vtu_fail_line(r, cur_line(r), "Piece: expected NumberOfCells >= 0, found %s",
                             nc ? quote(nc, q, sizeof q) : "none");
    /* Every point and cell takes at least one byte of the file, zlib packing up to ZLIB_MAX_RATIO. */
    uint64_t cap = (uint64_t)r->size * ZLIB_MAX_RATIO;
    if (r->point_count > INT32_MAX || (uint64_t)r->point_count > cap)
        return vtu_fail_line(r, cur_line(r), "Piece: NumberOfPoints %lld cannot be held in a file of %zu bytes "
                             "(at most 2^31-1 points)", (long long)r->point_count, r->size);
    if (r->cell_count > INT32_MAX || (uint64_t)r->cell_count > cap)
        return vtu_fail_line(r, cur_line(r), "Piece: NumberOfCells %lld cannot be held in a file of %zu bytes "
                             "(at most 2^31-1 cells)", (long long)r->cell_count, r->size);
    return 0;
}

static int start_array(vtu_reader *r, const XML_Char **atts)
{
    vtu_array *a = &r->cur;
    memset(a, 0, sizeof *a);
    a->line = cur_line(r);
    const char *name = attr(atts, "Name"), *type = attr(atts, "type"), *comps = attr(atts, "NumberOfComponents"),
               *format = attr(atts, "format"), *offset = attr(atts, "offset");
    snprintf(a->name, sizeof a->name, "%s", name && name[0] ? name : "unnamed");
    char q[64];
    switch (r->section) {
    case SEC_POINTS: a->role = ROLE_POINTS; break;
    case SEC_POINT_DATA: a->role = ROLE_POINT_FIELD; break;
    case SEC_CELL_DATA: a->role = ROLE_CELL_FIELD; break;
    default:
        if (!name)
            return vtu_fail_array(r, a, "Cells: expected a Name (connectivity, offsets, types, faces, faceoffsets)");
        if (!strcmp(name, "connectivity"))
            a->role = ROLE_CONN;
        else if (!strcmp(name, "offsets"))
            a->role = ROLE_OFFSETS;
        else if (!strcmp(name, "types"))
            a->role = ROLE_TYPES;
        else if (!strcmp(name, "faces"))
            a->role = ROLE_FACES;
        else if (!strcmp(name, "faceoffsets"))
            a->role = ROLE_FACEOFFSETS;
        else
            return 0; /* another array under Cells: ignored */
    }
    a->type = vtu_type_from_name(type);
    if (a->type == T_NONE)
        return vtu_fail_array(r, a, "expected a type (Int8..Int64, UInt8..UInt64, Float32, Float64), found %s",
                              type ? quote(type, q, sizeof q) : "none");
    int64_t nc = 1;
    if (comps && (parse_count(comps, &nc) || nc < 1 || nc > 1024))
        return vtu_fail_array(r, a, "expected NumberOfComponents from 1 to 1024, found %s", quote(comps, q, sizeof q));
    a->components = (int)nc;
    if (a->role == ROLE_POINTS && nc != 3)
        return vtu_fail_array(r, a, "Points: expected NumberOfComponents=\"3\", found %d", a->components);
    if (a->role != ROLE_POINTS && a->role != ROLE_POINT_FIELD && a->role != ROLE_CELL_FIELD && nc != 1)
        return vtu_fail_array(r, a, "expected NumberOfComponents=\"1\", found %d", a->components);
    if (a->role != ROLE_POINTS && a->role != ROLE_POINT_FIELD && a->role != ROLE_CELL_FIELD &&
        !vtu_is_int_type(a->type))
        return vtu_fail_array(r, a, "expected an integer type, found %s", vtu_type_name(a->type));
    if (!format || !strcmp(format, "ascii"))
        a->format = 0;
    else if (!strcmp(format, "binary"))
        a->format = 1;
    else if (!strcmp(format, "appended"))
        a->format = 2;
    else
        return vtu_fail_array(r, a, "expected format ascii, binary or appended, found \"%s\"",
                              quote(format, q, sizeof q));
    if (a->format == 2) {
        int64_t off;
        if (!offset || parse_count(offset, &off))
            return vtu_fail_array(r, a, "expected an offset >= 0 into the appended data, found %s",
                                  offset ? quote(offset, q, sizeof q) : "none");
        a->offset = (uint64_t)off;
    }
    for (int i = 0; i < r->array_count; i++)
        if (r->arrays[i].role == a->role && a->role != ROLE_POINT_FIELD && a->role != ROLE_CELL_FIELD)
            return vtu_fail_array(r, a, "expected one such array, found a second");
    r->in_array = 1;
    r->array_depth = r->depth;
    r->array_fed_offset = (int64_t)XML_GetCurrentByteIndex(r->parser);
    r->collect = a->format != 2;
    r->text_len = 0;
    r->borrowed = NULL;
    return 0;
}

static void XMLCALL on_start(void *user, const XML_Char *el, const XML_Char **atts)
{
    vtu_reader *r = user;
    if (r->failed)
        return;
    r->depth++;
    if (r->in_array)
        return; /* InformationKey and such inside a DataArray */
    char q[64];
    if (r->depth == 1) {
        if (strcmp(el, "VTKFile")) {
            vtu_fail_line(r, cur_line(r), "expected <VTKFile> (a VTK XML file), found <%s>", quote(el, q, sizeof q));
            return;
        }
        r->root_seen = 1;
        start_vtkfile(r, atts);
        return;
    }
    if (r->depth == 2 && !strcmp(el, "AppendedData")) {
        const char *enc = attr(atts, "encoding");
        if (enc && !strcmp(enc, "base64"))
            r->appended_base64 = 1;
        else if (enc && strcmp(enc, "raw")) {
            vtu_fail_line(r, cur_line(r), "AppendedData: expected encoding raw or base64, found \"%s\"",
                          quote(enc, q, sizeof q));
            return;
        }
        r->appended_seen = 1;
        return;
    }
    if (r->depth == 2 && !strcmp(el, "UnstructuredGrid")) {
        r->grid_depth = 2;
        return;
    }
    if (r->grid_depth && r->depth == 3 && !strcmp(el, "Piece")) {
        r->piece_depth = 3;
        start_piece(r, atts);
        return;
    }
    if (r->piece_depth && r->depth == 4) {
        r->section = !strcmp(el, "Points")      ? SEC_POINTS
                     : !strcmp(el, "Cells")     ? SEC_CELLS
                     : !strcmp(el, "PointData") ? SEC_POINT_DATA
                     : !strcmp(el, "CellData")  ? SEC_CELL_DATA
                                                : SEC_OTHER;
        return;
    }
    if (r->piece_depth && r->depth == 5 && r->section != SEC_OTHER && r->section != SEC_NONE &&
        !strcmp(el, "DataArray"))
        start_array(r, atts);
}

static int reserve_text(vtu_reader *r, size_t len);

/* The array's text as one buffer: the borrowed run copied in where it stands, unless all else is blanks
 * (the usual: the run is the whole array), when *s reads the run where it is. */
static int array_text(vtu_reader *r, bsrc *s)
{
    memset(s, 0, sizeof *s);
    s->b64 = 1;
    if (r->borrowed) {
        size_t blanks = 0;
        while (blanks < r->text_len && vtu_is_space((unsigned char)r->text[blanks]))
            blanks++;
        if (blanks == r->text_len) {
            s->p = (const unsigned char *)r->borrowed;
            s->len = r->borrowed_len;
            s->base = r->borrowed_at; /* places count from the text's start, as when copied */
            return 0;
        }
        size_t tail = r->text_len - r->borrowed_at;
        if (reserve_text(r, r->borrowed_len))
            return -1;
        memmove(r->text + r->borrowed_at + r->borrowed_len, r->text + r->borrowed_at, tail);
        memcpy(r->text + r->borrowed_at, r->borrowed, r->borrowed_len);
        r->text_len += r->borrowed_len;
        r->borrowed = NULL;
    }
    s->p = (const unsigned char *)r->text;
    s->len = r->text_len;
    return 0;
}

static void end_array(vtu_reader *r)
{
    vtu_array *a = &r->cur;
    r->in_array = 0;
    if (a->format == 0 && vtu_decode_ascii(r, a, r->text, r->text_len))
        return;
    if (a->format == 1) {
        bsrc s;
        if (array_text(r, &s) || vtu_decode_binary(r, a, &s))
            return;
    }
    keep_array(r, a);
}

static void XMLCALL on_end(void *user, const XML_Char *el)
{
    vtu_reader *r = user;
    (void)el;
    if (r->failed)
        return;
    if (r->in_array && r->depth == r->array_depth)
        end_array(r);
    if (r->depth == 4 && r->piece_depth)
        r->section = SEC_NONE;
    if (r->depth == 3 && r->piece_depth)
        r->piece_depth = 0;
    if (r->depth == 2 && r->grid_depth)
        r->grid_depth = 0;
    r->depth--;
}

/* Room for len more bytes of text. */
static int reserve_text(vtu_reader *r, size_t len)
{
    if (r->text_len + len > r->text_cap) {
        size_t cap = r->text_cap ? r->text_cap : 4096;
        while (cap < r->text_len + (size_t)len)
            cap *= 2;
        char *grown = realloc(r->text, cap);
        if (!grown)
            return vtu_fail_array(r, &r->cur, "out of memory for the array's text");
        r->text = grown;
        r->text_cap = cap;
    }
    return 0;
}

static void collect_text(vtu_reader *r, const char *s, size_t len)
{
    if (reserve_text(r, len))
        return;
    memcpy(r->text + r->text_len, s, len);
    r->text_len += len;
}

static void XMLCALL on_text(void *user, const XML_Char *s, int len)
{
    vtu_reader *r = user;
    if (r->failed || !r->in_array || !r->collect || r->depth != r->array_depth || len <= 0)
        return;
    collect_text(r, s, (size_t)len);
}

/* Base64 characters and blanks: what a binary DataArray's text is made of, and what expat would pass
 * on unchanged (no newline, so lines stay the same). A table: this runs over every byte of the file. */
#define B64_RANGE(first, last) [first ... last] = 1
static const unsigned char plain_base64_char[256] = {B64_RANGE('A', 'Z'), B64_RANGE('a', 'z'), B64_RANGE('0', '9'),
                                                     ['+'] = 1, ['/'] = 1, ['='] = 1, [' '] = 1, ['\t'] = 1};
#undef B64_RANGE

/* tpk_xml_take_fn: the base64 text right after the start tag of a binary DataArray (and the blanks
 * expat gave the text already) is collected here without expat, which would spend more time scanning
 * it than the whole decoding takes; expat goes on from the first other character. Only where the
 * element just started is that very tag, expat handed over all the blanks, and the run is long enough
 * to matter. */
/* How many bytes from `at` are plain_base64_char: 16 at a time where SSE2 is (every x86-64), by table
 * for the rest. The same count either way (test vtu.long_base64_runs_keep_error_places). */
static size_t plain_base64_run(const char *at, size_t left)
{
    size_t n = 0;
#ifdef __SSE2__
    const __m128i case_bit = _mm_set1_epi8(0x20), a_1 = _mm_set1_epi8('a' - 1), z_1 = _mm_set1_epi8('z' + 1);
    const __m128i d0_1 = _mm_set1_epi8('0' - 1), d9_1 = _mm_set1_epi8('9' + 1);
    const __m128i plus = _mm_set1_epi8('+'), slash = _mm_set1_epi8('/'), pad = _mm_set1_epi8('=');
    const __m128i space = _mm_set1_epi8(' '), tab = _mm_set1_epi8('\t');
    for (; left - n >= 16; n += 16) {
        __m128i v = _mm_loadu_si128((const __m128i *)(const void *)(at + n));
        __m128i folded = _mm_or_si128(v, case_bit); /* A-Z onto a-z; bytes >= 0x80 stay negative: refused */
        __m128i letter = _mm_and_si128(_mm_cmpgt_epi8(folded, a_1), _mm_cmpgt_epi8(z_1, folded));
        __m128i digit = _mm_and_si128(_mm_cmpgt_epi8(v, d0_1), _mm_cmpgt_epi8(d9_1, v));
        __m128i other = _mm_or_si128(_mm_or_si128(_mm_cmpeq_epi8(v, plus), _mm_cmpeq_epi8(v, slash)),
                                     _mm_or_si128(_mm_cmpeq_epi8(v, pad),
                                                  _mm_or_si128(_mm_cmpeq_epi8(v, space), _mm_cmpeq_epi8(v, tab))));
        unsigned ok = (unsigned)_mm_movemask_epi8(_mm_or_si128(_mm_or_si128(letter, digit), other));
        if (ok != 0xffffu)
            return n + (size_t)__builtin_ctz(~ok);
    }
#endif
    while (n < left && plain_base64_char[(unsigned char)at[n]])
        n++;
    return n;
}

static size_t take_base64(void *user, size_t fed_offset, size_t lead, const char *at, size_t left)
{
    vtu_reader *r = user;
    if (r->failed || !r->in_array || !r->collect || r->cur.format != 1 || r->depth != r->array_depth ||
        r->array_fed_offset != (int64_t)fed_offset || r->text_len != lead)
        return 0;
    size_t n = plain_base64_run(at, left);
    if (n < 4096)
        return 0;
    r->borrowed = at; /* read where it is at the array's end (array_text): no copy */
    r->borrowed_len = n;
    r->borrowed_at = r->text_len;
    return n;
}

static void XMLCALL on_doctype(void *user, const XML_Char *name, const XML_Char *sysid, const XML_Char *pubid,
                               int has_internal)
{
    vtu_reader *r = user;
    (void)name, (void)sysid, (void)pubid, (void)has_internal;
    vtu_fail_line(r, cur_line(r), "expected a VTK XML file, found a DOCTYPE declaration (not read)");
}

/* ---- Splitting off the appended data ------------------------------------------------------------ */

static const unsigned char *find(const unsigned char *p, size_t n, const char *word)
{
    size_t w = strlen(word);
    while (n >= w) {
        const unsigned char *c = memchr(p, word[0], n - w + 1);
        if (!c)
            return NULL;
        if (!memcmp(c, word, w))
            return c;
        n -= (size_t)(c - p) + 1;
        p = c + 1;
    }
    return NULL;
}

static const unsigned char *trim_space_back(const unsigned char *start, const unsigned char *end)
{
    while (end > start && vtu_is_space(end[-1]))
        end--;
    return end;
}

static int ends_with(const unsigned char *start, const unsigned char *end, const char *text)
{
    size_t n = strlen(text);
    return (size_t)(end - start) >= n && !memcmp(end - n, text, n);
}

/* Where the appended data ends: the file must end with "</AppendedData>" then "</VTKFile>" (whitespace
 * between and after them). Expat never sees this tail, so without the check a file cut anywhere after
 * the data it needs would be read as whole. */
static int appended_end(vtu_reader *r, const unsigned char *data_start)
{
    const unsigned char *end = trim_space_back(data_start, r->data + r->size);
    int whole = ends_with(data_start, end, "</VTKFile>");
    if (whole) {
        end = trim_space_back(data_start, end - strlen("</VTKFile>"));
        whole = ends_with(data_start, end, "</AppendedData>");
    }
    if (!whole)
        return vtu_fail_line(r, 0, "byte %zu: expected '</AppendedData>' and '</VTKFile>' ending the file after the "
                             "appended data, found end of file (truncated file?)", r->size);
    r->app_end = (size_t)(end - strlen("</AppendedData>") - r->data);
    return 0;
}

/* Length of the XML part to give expat: everything, or up to and including the AppendedData start tag
 * when there is one (then app_start is the byte after its '_' and app_end where its closing tag is). */
static int split_appended(vtu_reader *r, size_t *xml_len)
{
    *xml_len = r->size;
    const unsigned char *p = r->data, *end = r->data + r->size;
    for (;;) {
        const unsigned char *tag = find(p, (size_t)(end - p), "<AppendedData");
        if (!tag)
            return 0;
        const unsigned char *after = tag + 13;
        if (after < end && !vtu_is_space(*after) && *after != '>' && *after != '/') {
            p = after;
            continue;
        }
        const unsigned char *gt = memchr(after, '>', (size_t)(end - after));
        if (!gt)
            return vtu_fail_line(r, 0, "byte %zu: AppendedData: expected '>' closing the tag, found end of file",
                                 (size_t)(tag - r->data));
        if (gt[-1] == '/')
            return 0; /* an empty <AppendedData/>: nothing appended */
        const unsigned char *u = memchr(gt + 1, '_', (size_t)(end - gt - 1));
        if (!u)
            return vtu_fail_line(r, 0, "byte %zu: AppendedData: expected '_' marking the start of the data, found end "
                                 "of file", (size_t)(gt + 1 - r->data));
        for (const unsigned char *c = gt + 1; c < u; c++)
            if (!vtu_is_space(*c))
                return vtu_fail_line(r, 0, "byte %zu: AppendedData: expected '_' marking the start of the data, found "
                                     "'%c'", (size_t)(c - r->data), *c >= 32 && *c < 127 ? *c : '?');
        *xml_len = (size_t)(gt + 1 - r->data);
        r->app_start = (size_t)(u + 1 - r->data);
        return appended_end(r, u + 1);
    }
}

int vtu_parse_xml(vtu_reader *r)
{
    size_t xml_len;
    if (split_appended(r, &xml_len))
        return -1;
    int partial = xml_len < r->size;
    r->parser = XML_ParserCreate(NULL);
    if (!r->parser)
        return vtu_fail_line(r, 0, "out of memory for the XML parser");
    XML_SetUserData(r->parser, r);
    XML_SetElementHandler(r->parser, on_start, on_end);
    XML_SetCharacterDataHandler(r->parser, on_text);
    XML_SetStartDoctypeDeclHandler(r->parser, on_doctype);
    int rc = tpk_xml_parse_taking(r->parser, r->name, (const char *)r->data, xml_len, !partial, &r->failed, r->diag,
                                  "<DataArray", take_base64, r);
    XML_ParserFree(r->parser);
    r->parser = NULL;
    if (rc == 0 && partial && !r->appended_seen)
        return vtu_fail_line(r, 0, "byte %zu: expected the AppendedData element directly inside VTKFile, found it "
                             "elsewhere", r->app_start);
    return rc;
}

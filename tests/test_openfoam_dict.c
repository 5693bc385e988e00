/* OpenFOAM field files as tutorials write them (tools/import/openfoam/foam_dict.c): the icoFoam cavity's
 * polyMesh (tests/data/openfoam/cases/cavity_ascii) with a 0/ folder of field files using macros from the
 * same dictionary, from scopes and from included files, #inputMode, #remove and the N{v} short list; a
 * field using #calc is left out with a warning naming the file, the line and #calc (an error under
 * strict_fields), and the other fields still convert. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "harness.h"
#include "import/importers.h"
#include "tetpack_format.h"

#define CAVITY TPK_SOURCE_DIR "/tests/data/openfoam/cases/cavity_ascii"

static const char HEADER[] = "FoamFile\n{\n    version 2.0;\n    format ascii;\n    class %s;\n    object %s;\n}\n";

static void write_file(const char *dir, const char *name, const char *fmt, ...)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    if (!f)
        return;
    va_list ap;
    va_start(ap, fmt);
    vfprintf(f, fmt, ap);
    va_end(ap);
    fclose(f);
}

/* A field file: the header of `cls`, then `body`. */
static void write_field(const char *dir, const char *name, const char *cls, const char *body)
{
    char text[4096];
    snprintf(text, sizeof text, HEADER, cls, name);
    write_file(dir, name, "%s\n%s", text, body);
}

/* A fresh case: cavity's polyMesh (symlinked files) and an empty 0/. Returns the case folder. */
static const char *fresh_case(const char *tag)
{
    static char dir[700];
    char sub[900], from[900], to[1000];
    snprintf(dir, sizeof dir, "%s", tpk_temp_path(tag));
    mkdir(dir, 0777);
    snprintf(sub, sizeof sub, "%s/constant", dir);
    mkdir(sub, 0777);
    snprintf(sub, sizeof sub, "%s/constant/polyMesh", dir);
    mkdir(sub, 0777);
    static const char *const files[] = {"points", "faces", "owner", "neighbour"};
    for (int i = 0; i < 4; i++) {
        snprintf(from, sizeof from, CAVITY "/constant/polyMesh/%s", files[i]);
        snprintf(to, sizeof to, "%s/%s", sub, files[i]);
        unlink(to);
        if (symlink(from, to) != 0)
            return NULL;
    }
    snprintf(sub, sizeof sub, "%s/0", dir);
    mkdir(sub, 0777);
    snprintf(sub, sizeof sub, "%s/0/include", dir);
    mkdir(sub, 0777);
    return dir;
}

static const tpk_src_field *field_named(const tpk_mesh *m, const char *name)
{
    for (int i = 0; i < m->field_count; i++)
        if (strcmp(m->fields[i].name, name) == 0)
            return &m->fields[i];
    return NULL;
}

/* Every value of field `name` equals v[k % components]. */
static int field_is(const tpk_mesh *m, const char *name, int components, const float *v)
{
    const tpk_src_field *f = field_named(m, name);
    if (!f || f->components != components || f->association != TPK_ASSOC_TET) {
        fprintf(stderr, "field %s: %s\n", name, f ? "wrong kind" : "missing");
        return 0;
    }
    for (int64_t i = 0; i < m->cell_count * components; i++)
        if (f->values[i] != v[i % components]) {
            fprintf(stderr, "field %s: value %lld is %g, expected %g\n", name, (long long)i, f->values[i],
                    v[i % components]);
            return 0;
        }
    return 1;
}

typedef struct warnings {
    char text[4096];
    int count;
} warnings;

static void keep_warning(void *user, const char *text)
{
    warnings *w = user;
    size_t n = strlen(w->text);
    snprintf(w->text + n, sizeof w->text - n, "%s\n", text);
    w->count++;
}

static char case_dir[700];
static char zero[800];

static void macro_case(void)
{
    snprintf(case_dir, sizeof case_dir, "%s", fresh_case("macros"));
    snprintf(zero, sizeof zero, "%s/0", case_dir);
    /* the windAroundBuildings form: a value defined above, used below; a boundary include */
    write_field(zero, "k", "volScalarField",
                "kInlet 1.5; // a comment\ndimensions [0 2 -2 0 0 0 0];\ninternalField uniform $kInlet;\n"
                "boundaryField\n{\n    inlet { type fixedValue; value uniform $kInlet; }\n"
                "    #includeEtc \"caseDicts/setConstraintTypes\"\n}\n");
    /* scopes: into a sub-dictionary, from the top, from the parent, braces */
    write_field(zero, "s", "volScalarField",
                "top 4;\ninner { v 3; w $..top; deeper { x ${..v}; } }\nrootward $:inner.deeper.x;\n"
                "internalField uniform $inner.w;\nboundaryField { }\n");
    write_field(zero, "s2", "volScalarField",
                "inner { v 3; deeper { x ${..v}; } }\nrootward $:inner.deeper.x;\n"
                "internalField uniform $rootward;\nboundaryField { }\n");
    /* include (no FoamFile header, as tutorials' include/initialConditions), an optional missing one */
    write_file(zero, "include/initialConditions", "flowVelocity (10 0 -2.5);\npressure 7;\n");
    write_field(zero, "U", "volVectorField",
                "#include \"include/initialConditions\"\n#includeIfPresent \"include/none\"\n"
                "internalField uniform $flowVelocity;\nboundaryField { \".*\" { type calculated; } }\n");
    /* #inputMode protect keeps the first; overwrite replaces it; #remove hides it; the N{v} list */
    write_field(zero, "p", "volScalarField",
                "#include \"include/initialConditions\"\n#inputMode protect\npressure 9;\n#inputMode overwrite\n"
                "internalField uniform $pressure;\nboundaryField { }\n");
    write_field(zero, "r", "volScalarField",
                "a 1;\n#remove a\na 5;\ninternalField uniform $a;\nboundaryField { }\n");
    write_field(zero, "q", "volScalarField",
                "internalField nonuniform List<scalar> 400{0.25};\nboundaryField { }\n");
    /* #calc needs a compiler: refused by name, the field left out */
    write_field(zero, "nut", "volScalarField",
                "dimensions [0 2 -1 0 0 0 0];\n\ninternalField uniform #calc \"1.0 + 2.0\";\nboundaryField { }\n");
}

TPK_TEST(macros_scopes_includes_and_modes)
{
    macro_case();
    tpk_mesh m;
    warnings w = {{0}, 0};
    tpk_diag d = {0};
    d.warn = keep_warning;
    d.warn_user = &w;
    CHECK_MSG(tpk_import_any(case_dir, NULL, &m, &d) == 0, "%s", d.message);
    printf("%s", w.text);
    CHECK_EQ_INT(m.cell_count, 400);
    float k = 1.5f, four = 4, three = 3, u[3] = {10, 0, -2.5f}, seven = 7, five = 5, quarter = 0.25f;
    CHECK(field_is(&m, "k", 1, &k));
    CHECK(field_is(&m, "s", 1, &four));
    CHECK(field_is(&m, "s2", 1, &three));
    CHECK(field_is(&m, "U", 3, u));
    CHECK(field_is(&m, "p", 1, &seven));
    CHECK(field_is(&m, "r", 1, &five));
    CHECK(field_is(&m, "q", 1, &quarter));
    CHECK(field_named(&m, "nut") == NULL);
    CHECK_EQ_INT(w.count, 1);
    CHECK_MSG(strstr(w.text, "/0/nut:11: #calc is not evaluated") && strstr(w.text, "field nut left out"), "%s",
              w.text);
    tpk_mesh_free(&m);
}

TPK_TEST(strict_fields_refuses_the_calc)
{
    macro_case();
    tpk_mesh m;
    tpk_diag d = {0};
    d.strict_fields = 1;
    CHECK(tpk_import_any(case_dir, NULL, &m, &d) != 0);
    CHECK_MSG(strstr(d.message, "/0/nut:11: #calc is not evaluated"), "%s", d.message);
    CHECK(m.points == NULL && m.field_count == 0);
}

/* Each unreadable field: left out with its file, line and reason; the mesh and the rest still read. */
TPK_TEST(unreadable_fields_name_their_place)
{
    static const struct {
        const char *body, *words;
    } cases[] = {
        {"internalField uniform $missing;\n", "/0/f:9: $missing is not defined above its use"},
        {"internalField uniform $later;\nlater 1;\n", "$later is not defined above its use"},
        {"v 1;\n#remove v\ninternalField uniform $v;\n", "$v is not defined above its use"},
        {"#include \"nowhere\"\ninternalField uniform 1;\n", "#include \"nowhere\" at"},
        {"internalField uniform 1\n", "expected ';' to end entry 'internalField', found end of file"},
        {"internalField nonuniform List<scalar> 3(1 2 3);\n", "3 field values, expected 400"},
        {"internalField uniform \"text\";\n", "expected a uniform scalar value"},
        {"internalField #codeStream { code #{ os << 1; #}; };\n", "#codeStream is not evaluated"},
        {"x { y 1; }\ninternalField uniform $x;\n", "$x names a dictionary"},
        {"#inputMode error\nv 1;\nv 2;\ninternalField uniform $v;\n", "'v' is defined a second time"},
        {"internalField uniform 1;\nboundaryField { \"unclosed ; }\n", "never closed"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char tag[32];
        snprintf(tag, sizeof tag, "bad%zu", i);
        const char *dir = fresh_case(tag);
        char z[800];
        snprintf(z, sizeof z, "%s/0", dir);
        write_field(z, "f", "volScalarField", cases[i].body);
        write_field(z, "good", "volScalarField", "internalField uniform 2;\n");
        tpk_mesh m;
        warnings w = {{0}, 0};
        tpk_diag d = {0};
        d.warn = keep_warning;
        d.warn_user = &w;
        CHECK_MSG(tpk_import_any(dir, NULL, &m, &d) == 0, "%s", d.message);
        float two = 2;
        CHECK(field_is(&m, "good", 1, &two) && field_named(&m, "f") == NULL);
        CHECK_MSG(w.count == 1 && strstr(w.text, cases[i].words) && strstr(w.text, "/0/f:"),
                  "case %zu: expected '%s' in: %s", i, cases[i].words, w.text);
        tpk_mesh_free(&m);
    }
}

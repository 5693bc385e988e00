/* _tetpack: the CPython binding of libtetpack, the thin layer under python/tetpack/__init__.py.
 * libtetpack stays the only reader: this file only turns its calls into Python objects. Chunks come out
 * as flat uint8 NumPy arrays (zero-copy over the mapping when uncompressed, a decoded copy otherwise);
 * the Python layer gives them their dtype and shape.
 *
 * Lifetime: the tpk_file lives in a Mapping object. A File holds one reference to it, and every
 * zero-copy array holds another as its NumPy base. File.close() drops the File's reference and marks the
 * File closed (later calls raise tetpack.Error), so the file is unmapped at once when no array points
 * into it, and otherwise when the last such array dies: an array never outlives the bytes it shows. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>

#include "tetpack.h"

static PyObject *tetpack_error; /* tetpack.Error: .code (tpk_result), .code_name, .message */

/* ---- Mapping: owns the open tpk_file ------------------------------------------------------------- */

typedef struct {
    PyObject_HEAD
    tpk_file *file;
} Mapping;

static void mapping_dealloc(Mapping *self)
{
    tpk_close(self->file);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyTypeObject MappingType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "tetpack._tetpack.Mapping",
    .tp_basicsize = sizeof(Mapping),
    .tp_dealloc = (destructor)mapping_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "An open, mapped .tpk; kept alive by its File and by every array viewing it.",
};

/* ---- Errors ----------------------------------------------------------------------------------- */

/* Set obj.name = value and drop the reference to value (NULL value: an error already set). */
static int set_attr_steal(PyObject *obj, const char *name, PyObject *value)
{
    int rc = value ? PyObject_SetAttrString(obj, name, value) : -1;
    Py_XDECREF(value);
    return rc;
}

/* Raise tetpack.Error(message) with the library's code; returns NULL for `return raise_result(...)`. */
static PyObject *raise_result(tpk_result code, const char *detail)
{
    const char *message = detail && detail[0] ? detail : tpk_result_string(code);
    PyObject *exc = PyObject_CallFunction(tetpack_error, "s", message);
    if (!exc)
        return NULL;
    if (set_attr_steal(exc, "code", PyLong_FromLong((long)code)) == 0 &&
        set_attr_steal(exc, "code_name", PyUnicode_FromString(tpk_result_string(code))) == 0 &&
        set_attr_steal(exc, "message", PyUnicode_FromString(message)) == 0)
        PyErr_SetObject(tetpack_error, exc);
    Py_DECREF(exc);
    return NULL;
}

static PyObject *raise_file(tpk_file *file, tpk_result code)
{
    return raise_result(code, tpk_error_text(file));
}

/* ---- File --------------------------------------------------------------------------------------- */

typedef struct {
    PyObject_HEAD
    Mapping *mapping; /* NULL once closed */
} File;

/* The open mapping with a new reference (so a close() from another thread cannot free it under a call
 * that released the GIL), or NULL with tetpack.Error set when the file is closed. */
static Mapping *acquire(File *self)
{
    if (!self->mapping) {
        raise_result(TPK_ERR_BAD_STATE, "I/O operation on a closed tetpack file");
        return NULL;
    }
    Py_INCREF(self->mapping);
    return self->mapping;
}

static int file_init(File *self, PyObject *args, PyObject *kwds)
{
    static char *keywords[] = {"path", "verify_all", NULL};
    PyObject *path_obj;
    int verify_all = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "O&|p", keywords, PyUnicode_FSConverter, &path_obj, &verify_all))
        return -1;
    tpk_open_options options = {.size = sizeof options, .flags = verify_all ? TPK_OPEN_VERIFY_ALL : 0};
    char err[512] = "";
    tpk_file *file = NULL;
    tpk_result r;
    const char *path = PyBytes_AS_STRING(path_obj);
    Py_BEGIN_ALLOW_THREADS
    r = tpk_open_path(&file, path, &options, err, sizeof err);
    Py_END_ALLOW_THREADS
    Py_DECREF(path_obj);
    if (r != TPK_OK) {
        raise_result(r, err);
        return -1;
    }
    Mapping *mapping = PyObject_New(Mapping, &MappingType);
    if (!mapping) {
        tpk_close(file);
        return -1;
    }
    mapping->file = file;
    Py_XSETREF(self->mapping, mapping);
    return 0;
}

static void file_dealloc(File *self)
{
    Py_CLEAR(self->mapping);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *file_close(File *self, PyObject *Py_UNUSED(ignored))
{
    Py_CLEAR(self->mapping);
    Py_RETURN_NONE;
}

static PyObject *file_closed(File *self, void *Py_UNUSED(closure))
{
    return PyBool_FromLong(self->mapping == NULL);
}

static PyObject *vec3(const double v[3])
{
    return Py_BuildValue("(ddd)", v[0], v[1], v[2]);
}

static PyObject *file_info(File *self, PyObject *Py_UNUSED(ignored))
{
    Mapping *m = acquire(self);
    if (!m)
        return NULL;
    tpk_file_info info;
    tpk_result r = tpk_get_info(m->file, &info);
    PyObject *result = NULL;
    if (r != TPK_OK)
        raise_file(m->file, r);
    else
        result = Py_BuildValue("{s:(HH),s:K,s:K,s:K,s:K,s:K,s:N,s:N,s:N}", "version", info.version_major,
                               info.version_minor, "file_size", (unsigned long long)info.file_size, "vertex_count",
                               (unsigned long long)info.vertex_count, "tet_count",
                               (unsigned long long)info.tet_count, "shell_face_count",
                               (unsigned long long)info.shell_face_count, "chunk_count",
                               (unsigned long long)info.chunk_count, "origin", vec3(info.origin), "bounds_min",
                               vec3(info.bounds_min), "bounds_max", vec3(info.bounds_max));
    Py_DECREF(m);
    return result;
}

static PyObject *entry_dict(const tpk_dir_entry *e)
{
    char tag[5] = {(char)(e->tag & 0xff), (char)(e->tag >> 8 & 0xff), (char)(e->tag >> 16 & 0xff),
                   (char)(e->tag >> 24 & 0xff), 0};
    return Py_BuildValue("{s:s,s:I,s:i,s:i,s:I,s:I,s:I,s:K,s:K,s:K,s:K,s:K}", "tag", tag, "tag_value", e->tag,
                         "codec", (int)e->codec, "elem_type", (int)e->elem_type, "elem_size", e->elem_size,
                         "index", e->index, "step", e->step, "elem_count", (unsigned long long)e->elem_count,
                         "offset", (unsigned long long)e->offset, "stored_size",
                         (unsigned long long)e->stored_size, "raw_size", (unsigned long long)e->raw_size,
                         "checksum", (unsigned long long)e->checksum);
}

static PyObject *file_chunks(File *self, PyObject *Py_UNUSED(ignored))
{
    Mapping *m = acquire(self);
    if (!m)
        return NULL;
    tpk_file_info info;
    tpk_result r = tpk_get_info(m->file, &info);
    PyObject *list = r == TPK_OK ? PyList_New(0) : raise_file(m->file, r);
    for (uint64_t i = 0; list && i < info.chunk_count; i++) {
        tpk_dir_entry e;
        r = tpk_get_chunk(m->file, i, &e);
        PyObject *d = r == TPK_OK ? entry_dict(&e) : raise_file(m->file, r);
        if (!d || PyList_Append(list, d) < 0)
            Py_CLEAR(list);
        Py_XDECREF(d);
    }
    Py_DECREF(m);
    return list;
}

/* find_chunk(tag, index=0, step=0) -> chunk number, or None when the file has no such chunk. */
static PyObject *file_find_chunk(File *self, PyObject *args)
{
    unsigned int tag, index = 0, step = 0;
    if (!PyArg_ParseTuple(args, "I|II", &tag, &index, &step))
        return NULL;
    Mapping *m = acquire(self);
    if (!m)
        return NULL;
    uint64_t i;
    tpk_result r = tpk_find_chunk(m->file, tag, index, step, &i);
    PyObject *result;
    if (r == TPK_OK)
        result = PyLong_FromUnsignedLongLong(i);
    else if (r == TPK_ERR_NOT_FOUND)
        result = Py_NewRef(Py_None);
    else
        result = raise_file(m->file, r);
    Py_DECREF(m);
    return result;
}

/* A read-only uint8 array over `size` mapped bytes whose base is the mapping (steals nothing). */
static PyObject *view_array(Mapping *m, const void *data, uint64_t size)
{
    npy_intp dims[1] = {(npy_intp)size};
    PyObject *array = PyArray_New(&PyArray_Type, 1, dims, NPY_UINT8, NULL, (void *)data, 0, 0, NULL);
    if (!array)
        return NULL;
    PyArray_CLEARFLAGS((PyArrayObject *)array, NPY_ARRAY_WRITEABLE);
    Py_INCREF(m);
    if (PyArray_SetBaseObject((PyArrayObject *)array, (PyObject *)m) < 0) {
        Py_DECREF(array);
        return NULL;
    }
    return array;
}

/* A new uint8 array holding chunk i decoded (zstd) and checked. */
static PyObject *decoded_array(Mapping *m, uint64_t i, uint64_t size)
{
    npy_intp dims[1] = {(npy_intp)size};
    PyObject *array = PyArray_SimpleNew(1, dims, NPY_UINT8);
    if (!array)
        return NULL;
    void *dst = PyArray_DATA((PyArrayObject *)array);
    tpk_result r;
    Py_BEGIN_ALLOW_THREADS
    r = tpk_read_chunk(m->file, i, dst, size);
    Py_END_ALLOW_THREADS
    if (r != TPK_OK) {
        Py_DECREF(array);
        return raise_file(m->file, r);
    }
    return array;
}

/* chunk_bytes(i) -> (uint8 array, zero_copy): a view into the mapping for an uncompressed chunk, a
 * decoded copy otherwise. Either way the checksum has been checked (unless opened trusted). */
static PyObject *file_chunk_bytes(File *self, PyObject *args)
{
    unsigned long long i;
    if (!PyArg_ParseTuple(args, "K", &i))
        return NULL;
    Mapping *m = acquire(self);
    if (!m)
        return NULL;
    tpk_dir_entry e = {0};
    tpk_result r = tpk_get_chunk(m->file, i, &e);
    PyObject *array = NULL;
    int zero_copy = e.codec == TPK_CODEC_NONE;
    if (r != TPK_OK) {
        raise_file(m->file, r);
    } else if (zero_copy) {
        const void *data;
        uint64_t size;
        Py_BEGIN_ALLOW_THREADS /* the first view checks the checksum: a pass over the chunk */
        r = tpk_view_chunk(m->file, i, &data, &size);
        Py_END_ALLOW_THREADS
        array = r == TPK_OK ? view_array(m, data, size) : raise_file(m->file, r);
    } else {
        array = decoded_array(m, i, e.raw_size);
    }
    Py_DECREF(m);
    return array ? Py_BuildValue("(NO)", array, zero_copy ? Py_True : Py_False) : NULL;
}

static PyObject *file_verify(File *self, PyObject *Py_UNUSED(ignored))
{
    Mapping *m = acquire(self);
    if (!m)
        return NULL;
    tpk_result r;
    Py_BEGIN_ALLOW_THREADS
    r = tpk_verify(m->file);
    Py_END_ALLOW_THREADS
    PyObject *result = r == TPK_OK ? Py_NewRef(Py_None) : raise_file(m->file, r);
    Py_DECREF(m);
    return result;
}

static PyObject *file_fields(File *self, PyObject *Py_UNUSED(ignored))
{
    Mapping *m = acquire(self);
    if (!m)
        return NULL;
    uint32_t count = tpk_field_count(m->file);
    PyObject *list = PyList_New(0);
    for (uint32_t i = 0; list && i < count; i++) {
        tpk_field_desc d;
        tpk_result r = tpk_get_field(m->file, i, &d);
        PyObject *item = r != TPK_OK ? raise_file(m->file, r)
                                     : Py_BuildValue("{s:s#,s:s#,s:s,s:I,s:I,s:d,s:d}", "name", d.name,
                                                     (Py_ssize_t)strnlen(d.name, sizeof d.name), "units", d.units,
                                                     (Py_ssize_t)strnlen(d.units, sizeof d.units), "association",
                                                     d.association == TPK_ASSOC_TET ? "tet" : "point", "steps",
                                                     d.step_count, "components", d.components ? d.components : 1,
                                                     "min", (double)d.min_value, "max", (double)d.max_value);
        if (!item || PyList_Append(list, item) < 0)
            Py_CLEAR(list);
        Py_XDECREF(item);
    }
    Py_DECREF(m);
    return list;
}

/* time(step) -> the TIME value of a step, or None when the file stores no times. */
static PyObject *file_time(File *self, PyObject *args)
{
    unsigned int step;
    if (!PyArg_ParseTuple(args, "I", &step))
        return NULL;
    Mapping *m = acquire(self);
    if (!m)
        return NULL;
    double t;
    tpk_result r = tpk_get_time(m->file, step, &t);
    PyObject *result = r == TPK_OK            ? PyFloat_FromDouble(t)
                       : r == TPK_ERR_NOT_FOUND ? Py_NewRef(Py_None)
                                                : raise_file(m->file, r);
    Py_DECREF(m);
    return result;
}

/* recover_tets(layout) -> int32 array (tet_count, 4), positively oriented, from TT32, TT20 or TT16. */
static PyObject *file_recover_tets(File *self, PyObject *args)
{
    int layout;
    if (!PyArg_ParseTuple(args, "i", &layout))
        return NULL;
    if (layout != TPK_LAYOUT_TET32 && layout != TPK_LAYOUT_TET20 && layout != TPK_LAYOUT_TET16)
        return raise_result(TPK_ERR_INVALID_ARGUMENT, "layout must be 32, 20 or 16");
    Mapping *m = acquire(self);
    if (!m)
        return NULL;
    tpk_mesh_arrays mesh;
    PyObject *array = NULL;
    tpk_result r;
    Py_BEGIN_ALLOW_THREADS
    r = tpk_load_arrays(m->file, (tpk_layout)layout, NULL, 0, &mesh);
    Py_END_ALLOW_THREADS
    if (r != TPK_OK) {
        raise_file(m->file, r);
    } else {
        npy_intp dims[2] = {(npy_intp)mesh.tet_count, 4};
        array = PyArray_SimpleNew(2, dims, NPY_INT32);
        if (array) {
            int32_t *dst = PyArray_DATA((PyArrayObject *)array);
            Py_BEGIN_ALLOW_THREADS
            r = tpk_recover_tets(&mesh, dst);
            Py_END_ALLOW_THREADS
            if (r != TPK_OK) {
                Py_CLEAR(array);
                raise_result(r, "cannot recover the tets' vertices from this layout");
            }
        }
    }
    Py_DECREF(m);
    return array;
}

static PyMethodDef file_methods[] = {
    {"close", (PyCFunction)file_close, METH_NOARGS,
     "Close the file: later calls raise tetpack.Error; arrays already taken stay valid (they keep the mapping)."},
    {"info", (PyCFunction)file_info, METH_NOARGS, "Header values as a dict."},
    {"chunks", (PyCFunction)file_chunks, METH_NOARGS, "The chunk directory as a list of dicts."},
    {"find_chunk", (PyCFunction)file_find_chunk, METH_VARARGS, "find_chunk(tag, index=0, step=0) -> int or None"},
    {"chunk_bytes", (PyCFunction)file_chunk_bytes, METH_VARARGS,
     "chunk_bytes(i) -> (uint8 array, zero_copy): a view for uncompressed chunks, decoded otherwise."},
    {"verify", (PyCFunction)file_verify, METH_NOARGS, "Check every checksum and the cross-chunk rules."},
    {"field_descs", (PyCFunction)file_fields, METH_NOARGS, "Field descriptors as a list of dicts."},
    {"time", (PyCFunction)file_time, METH_VARARGS, "time(step) -> float or None"},
    {"recover_tets", (PyCFunction)file_recover_tets, METH_VARARGS,
     "recover_tets(layout) -> int32 (tet_count, 4), positively oriented."},
    {NULL, NULL, 0, NULL},
};

static PyGetSetDef file_getset[] = {
    {"closed", (getter)file_closed, NULL, "True after close()", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyTypeObject FileType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "tetpack._tetpack.File",
    .tp_basicsize = sizeof(File),
    .tp_dealloc = (destructor)file_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_BASETYPE,
    .tp_doc = "File(path, verify_all=False): an open .tpk (libtetpack handle over a read-only mapping).",
    .tp_methods = file_methods,
    .tp_getset = file_getset,
    .tp_init = (initproc)file_init,
    .tp_new = PyType_GenericNew,
};

/* ---- Module ------------------------------------------------------------------------------------- */

static PyObject *result_string(PyObject *Py_UNUSED(module), PyObject *args)
{
    int code;
    if (!PyArg_ParseTuple(args, "i", &code))
        return NULL;
    return PyUnicode_FromString(tpk_result_string((tpk_result)code));
}

static PyMethodDef module_methods[] = {
    {"result_string", result_string, METH_VARARGS, "The library's name for a result code."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT, "_tetpack", "CPython binding of libtetpack (see tetpack/__init__.py).", -1,
    module_methods, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit__tetpack(void)
{
    import_array();
    if (PyType_Ready(&MappingType) < 0 || PyType_Ready(&FileType) < 0)
        return NULL;
    PyObject *module = PyModule_Create(&module_def);
    if (!module)
        return NULL;
    tetpack_error = PyErr_NewExceptionWithDoc("tetpack.Error",
                                              "A libtetpack failure: .code is the tpk_result, .code_name its "
                                              "name, .message the library's detailed text.",
                                              PyExc_RuntimeError, NULL);
    if (!tetpack_error || PyModule_AddObjectRef(module, "Error", tetpack_error) < 0 ||
        PyModule_AddObjectRef(module, "File", (PyObject *)&FileType) < 0 ||
        PyModule_AddStringConstant(module, "LIBRARY_VERSION", TPK_LIBRARY_VERSION) < 0 ||
        PyModule_AddIntConstant(module, "FORMAT_VERSION_MAJOR", TPK_VERSION_MAJOR) < 0) {
        Py_DECREF(module);
        return NULL;
    }
    return module;
}

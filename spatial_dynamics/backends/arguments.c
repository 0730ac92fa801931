/* Copyright 2026 spatial_dynamics contributors
 * SPDX-License-Identifier: Apache-2.0
 *
 * The argument reader of the single-state entries: q, qd, qdd and gravity read once each
 * into C doubles (as_doubles) from a 1-D numpy array of float64, float32 or integers (any
 * strides) through the numpy C API, a list or tuple of Python floats and ints, or another
 * 1-D buffer of such numbers through the buffer protocol; anything else (a batch, float16,
 * longdouble, a wrong length, other objects) is declined, so that the Python caller takes
 * its general path, which validates and names the argument. And the C-contiguous float64
 * tables of the batch entries and of f_body (get_table).
 */
#include "_compiled.h"

#include <string.h>

/* The item types read, as numpy type numbers, their buffer-protocol codes and their sizes
 * (same order); anything else (float16, longdouble, complex, objects, datetimes, …) is
 * declined. */
static const int READ_TYPES[] = {NPY_DOUBLE, NPY_FLOAT, NPY_BOOL, NPY_BYTE, NPY_UBYTE,
                                 NPY_SHORT, NPY_USHORT, NPY_INT, NPY_UINT, NPY_LONG, NPY_ULONG,
                                 NPY_LONGLONG, NPY_ULONGLONG};
static const char READ_CODES[] = "df?bBhHiIlLqQ";
static const Py_ssize_t READ_SIZES[] = {
    sizeof(double), sizeof(float), sizeof(npy_bool), sizeof(npy_byte), sizeof(npy_ubyte),
    sizeof(npy_short), sizeof(npy_ushort), sizeof(npy_int), sizeof(npy_uint), sizeof(npy_long),
    sizeof(npy_ulong), sizeof(npy_longlong), sizeof(npy_ulonglong)};

/* n items of numpy type `type` from p, `step` bytes apart, as doubles. */
static int
read_strided(const char *p, Py_ssize_t n, Py_ssize_t step, int type, double *out)
{
#define READ(ctype)                                                                 \
    do {                                                                            \
        for (Py_ssize_t i = 0; i < n; i++) {                                        \
            ctype x;                                                                \
            memcpy(&x, p + i * step, sizeof x);                                     \
            out[i] = (double)x;                                                     \
        }                                                                           \
    } while (0)
    switch (type) {
    case NPY_DOUBLE: READ(double); break;
    case NPY_FLOAT: READ(npy_float); return AS_FLOAT;
    case NPY_BOOL: READ(npy_bool); break;
    case NPY_BYTE: READ(npy_byte); break;
    case NPY_UBYTE: READ(npy_ubyte); break;
    case NPY_SHORT: READ(npy_short); break;
    case NPY_USHORT: READ(npy_ushort); break;
    case NPY_INT: READ(npy_int); break;
    case NPY_UINT: READ(npy_uint); break;
    case NPY_LONG: READ(npy_long); break;
    case NPY_ULONG: READ(npy_ulong); break;
    case NPY_LONGLONG: READ(npy_longlong); break;
    case NPY_ULONGLONG: READ(npy_ulonglong); break;
    default: return DECLINED;
    }
#undef READ
    return AS_DOUBLE;
}

/* The items of a 1-D buffer v: shape and strides may be NULL (an exporter of a C-contiguous
 * buffer may leave them out, as ctypes does), the items then follow each other. */
static Py_ssize_t
buffer_items(const Py_buffer *v)
{
    if (v->ndim != 1 || v->itemsize <= 0)
        return -1;
    return v->shape != NULL ? v->shape[0] : v->len / v->itemsize;
}

/* The 1-D buffer v (buffer_items items, any strides, no suboffsets) by its format: a native
 * single-item code of READ_CODES whose size is the C type's, else DECLINED (as numpy would
 * see it: the same items as read_strided takes from an array). */
static int
read_buffer(const Py_buffer *v, double *out)
{
    if (v->suboffsets != NULL && v->suboffsets[0] >= 0)
        return DECLINED;        /* pointers to the items, not the items */
    const char *fmt = v->format ? v->format : "B";
#if PY_LITTLE_ENDIAN
    if (*fmt == '@' || *fmt == '=' || *fmt == '<')
#else
    if (*fmt == '@' || *fmt == '=' || *fmt == '>' || *fmt == '!')
#endif
        fmt++;
    const char *code = fmt[0] != '\0' && fmt[1] == '\0' ? strchr(READ_CODES, fmt[0]) : NULL;
    if (code == NULL || READ_SIZES[code - READ_CODES] != v->itemsize)
        return DECLINED;
    const Py_ssize_t step = v->strides != NULL ? v->strides[0] : v->itemsize;
    return read_strided(v->buf, buffer_items(v), step, READ_TYPES[code - READ_CODES], out);
}

/* ``obj`` as n doubles: AS_DOUBLE or AS_FLOAT (read from float32); DECLINED when it is not
 * one state of n numbers this entry reads; never an error. Read: a 1-D numpy array (not
 * of a subclass) of READ_TYPES in native byte order (any strides), a list or tuple of Python floats and ints,
 * another 1-D buffer of such items. */
int
as_doubles(PyObject *obj, Py_ssize_t n, double *out)
{
    if (PyArray_Check(obj)) {
        PyArrayObject *a = (PyArrayObject *)obj;
        if (!PyArray_CheckExact(obj))
            return DECLINED;    /* a subclass (a masked array: its mask) is the caller's */
        if (PyArray_NDIM(a) != 1 || PyArray_DIM(a, 0) != n || !PyArray_ISNOTSWAPPED(a))
            return DECLINED;
        if (PyArray_TYPE(a) == NPY_DOUBLE && PyArray_STRIDE(a, 0) == sizeof(double)) {
            memcpy(out, PyArray_BYTES(a), sizeof(double) * n);  /* the common case */
            return AS_DOUBLE;
        }
        return read_strided(PyArray_BYTES(a), n, PyArray_STRIDE(a, 0), PyArray_TYPE(a), out);
    }
    if (PyList_CheckExact(obj) || PyTuple_CheckExact(obj)) {
        if (PySequence_Fast_GET_SIZE(obj) != n)
            return DECLINED;
        PyObject **items = PySequence_Fast_ITEMS(obj);
        for (Py_ssize_t i = 0; i < n; i++) {
            PyObject *x = items[i];
            if (PyFloat_Check(x)) {
                out[i] = PyFloat_AS_DOUBLE(x);
            } else if (PyLong_Check(x)) {
                out[i] = PyLong_AsDouble(x);
                if (out[i] == -1.0 && PyErr_Occurred()) {
                    PyErr_Clear();
                    return DECLINED;
                }
            } else {
                return DECLINED;
            }
        }
        return AS_DOUBLE;
    }
    if (PyBytes_Check(obj) || PyByteArray_Check(obj) || !PyObject_CheckBuffer(obj))
        return DECLINED;
    Py_buffer v;
    if (PyObject_GetBuffer(obj, &v, PyBUF_STRIDES | PyBUF_FORMAT) < 0) {
        PyErr_Clear();
        return DECLINED;
    }
    int read = buffer_items(&v) == n ? read_buffer(&v, out) : DECLINED;
    PyBuffer_Release(&v);
    return read;
}

/* The buffer of obj, C-contiguous float64 (writable if asked); -1 with an error if not. */
int
get_table(PyObject *obj, Py_buffer *v, int writable, const char *what)
{
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, v, flags) < 0)
        return -1;
    const char *fmt = v->format ? v->format : "B";
    if (*fmt == '@' || *fmt == '=' || *fmt == '<')
        fmt++;
    if (strcmp(fmt, "d") != 0) {
        PyBuffer_Release(v);
        PyErr_Format(PyExc_TypeError, "%s must be C-contiguous float64", what);
        return -1;
    }
    return 0;
}

/* Copyright 2026 spatial_dynamics contributors
 * SPDX-License-Identifier: Apache-2.0
 *
 * spatial_dynamics.backends._compiled: the kernels of _kernels_generated.h (generated from
 * spatial_dynamics/algorithms by codegen.py) as a CPython extension, built by setup.py.
 *
 * This file only moves data. A Kernels object holds a copy of a model's table (the rows of
 * backends/layout.py, prepared once in Python). Each algorithm is one row of ALGORITHMS
 * (which joint vectors it reads, whether gravity and external forces, which generated
 * kernel it runs); one generic single-state entry and one generic batch entry serve them
 * all, as the module's functions rnea, mass_matrix, rnea_batch, ...
 *
 * The single-state entries (METH_FASTCALL) read q, qd, qdd and gravity once each into C
 * doubles: a 1-D numpy array of float64, float32 or integers (any strides) through the
 * numpy C API, a list or tuple of Python floats and ints, or another 1-D buffer of such
 * numbers through the buffer protocol; anything else (a batch, float16, longdouble, a wrong
 * length, other objects) returns None so that the Python caller takes its general path,
 * which validates and names the argument. Results are new numpy arrays, float32 when every
 * joint vector is float32 (the dtype numpy's promotion gives; computed in float64 and
 * rounded once), else float64. The batch entries take C-contiguous float64 arrays prepared
 * by the caller, release the GIL and let POSIX threads claim the states chunk by chunk
 * (run_batch); the RNEA of a batch runs several states at once in the SIMD lanes of
 * _kernels_generated.h.
 *
 * The numpy C API, version-targeted: built against numpy 2.x headers, the extension also
 * runs on numpy 1.23 and later (NPY_TARGET_VERSION; 1.23 is the oldest numpy for Python
 * 3.11), e.g. Ubuntu 24.04's 1.26. Built against numpy 1.x headers it runs on numpy 1.x
 * only (numpy's rule); import_array then fails on 2.x and the package runs on plain Python,
 * with compiled.py's warning.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <structmember.h>

#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#define NPY_TARGET_VERSION NPY_1_23_API_VERSION
#include <numpy/arrayobject.h>

#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#ifndef _WIN32
#include <pthread.h>
#endif

/* Generated from spatial_dynamics/algorithms into the build directory by setup.py (on the
 * include path), never a file of the sources. */
#include <_kernels_generated.h>
#ifndef KERNELS_SHA256
#define KERNELS_SHA256 ""   /* setup.py defines the SHA-256 of the header it generated */
#endif

/* The interface this file offers to compiled.py, which refuses a build of another (a stale
 * extension left beside newer sources): raise it with every change of an entry. */
#define API 5
/* Scratch of a single call on the C stack up to this many doubles (16 KiB), else the heap. */
#define STACK_DOUBLES 2048
/* Largest number of threads of one batch; each gets at least MIN_WORK body-states (states x
 * bodies, ~0.2 ms of work): starting a thread, and waiting for a core on a busy machine,
 * must cost less than what it takes over. */
#define MAX_THREADS 64
#define MIN_WORK 4096
/* The threads of a batch claim its states a chunk at a time, about CHUNK_WORK body-states
 * (~25 us) in a multiple of 8 states (the widest SIMD lanes): a thread that a busy machine
 * holds back leaves the rest to the others, and the lanes group the same states whatever
 * the thread count. */
#define CHUNK_WORK 1024

/* Largest count of doubles of one array or scratch: a few such counts add up, and times
 * sizeof(double), without overflow in Py_ssize_t. */
#define MAX_DOUBLES (PY_SSIZE_T_MAX / 64)

/* a x b in *out, or -1 when either is negative or the product exceeds `most`. */
static int
checked_mul(Py_ssize_t a, Py_ssize_t b, Py_ssize_t most, Py_ssize_t *out)
{
    if (a < 0 || b < 0 || (a != 0 && b > most / a))
        return -1;
    *out = a * b;
    return 0;
}

/* ------------------------------------------------------------------------------------------
 * Kernels: one model's table */

typedef struct {
    PyObject_HEAD
    double *K;          /* rows x WIDTH, row-major */
    long rows;          /* NB + 1 */
    long n;             /* joints (len(q)) */
    double *zeros;      /* nv zeros: qd, qdd of the terms at rest */
    long nv;            /* velocity coordinates (len(qd), len(tau)); n for a fixed base */
} KernelsObject;

/* Whether the rows of table K (rows x WIDTH) index q (nq numbers) and q̇ (nv numbers) within
 * bounds, each body's parent before it: a 1-DoF joint one coordinate of each, a free-flyer
 * (code FF) 7 of q and 6 of q̇ (the `dof` column), so that no table makes the kernels read or
 * write out of bounds. */
static int
rows_fit(const double *K, long rows, double nq, double nv)
{
    int ok = nv >= 0.0 && nv <= nq && nv == (double)(long)nv;
    double q_end = 0.0, v_end = 0.0;     /* every coordinate is some body's joint's */
    for (long i = 1; ok && i < rows; i++) {
        const double *row = K + i * WIDTH;
        const double code = row[1], k = row[QIDX], kv = row[VIDX], dof = row[DOF];
        const double width = code == FF ? 7.0 : 1.0;
        ok = row[0] >= 0.0 && row[0] < (double)i && row[0] == (double)(long)row[0]
             && code >= 0.0 && code <= (double)FF && code == (double)(long)code
             && k >= 0.0 && k + width <= nq && k == (double)(long)k
             && kv >= 0.0 && kv + dof <= nv && kv == (double)(long)kv
             && dof == (code == FF ? 6.0 : 1.0);
        q_end = k + width > q_end ? k + width : q_end;
        v_end = kv + dof > v_end ? kv + dof : v_end;
    }
    return ok && q_end == nq && v_end == nv;
}

static PyTypeObject KernelsType;

static void
kernels_dealloc(KernelsObject *self)
{
    PyMem_Free(self->K);
    PyMem_Free(self->zeros);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *
kernels_new(PyTypeObject *type, PyObject *args, PyObject *kwds)
{
    PyObject *table;
    static char *keywords[] = {"table", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "O:Kernels", keywords, &table))
        return NULL;
    Py_buffer v;
    if (PyObject_GetBuffer(table, &v, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0)
        return NULL;
    const char *fmt = v.format ? v.format : "B";
    if (*fmt == '@' || *fmt == '=' || *fmt == '<')
        fmt++;
    if (strcmp(fmt, "d") != 0 || v.ndim != 2 || v.shape[1] != WIDTH || v.shape[0] < 1) {
        PyBuffer_Release(&v);
        PyErr_Format(PyExc_ValueError,
                     "Kernels: table must be a C-contiguous float64 array of shape (NB + 1, %d)",
                     (int)WIDTH);
        return NULL;
    }
    const double *K = (const double *)v.buf;
    long rows = (long)v.shape[0];
    double n = K[QIDX];
    /* at most one joint per body (mimic joints share one), each at most 7 coordinates of q
     * (a free-flyer), so n < 7 rows */
    int ok = n >= 0.0 && n < 7.0 * (double)rows && n == (double)(long)n;
    /* The kernels index q, the scratch and their parents by these columns: check them once,
     * so no table reaches the kernels that could make them read or write out of bounds. */
    ok = ok && rows_fit(K, rows, n, K[VIDX]);
    if (!ok) {
        PyBuffer_Release(&v);
        PyErr_SetString(PyExc_ValueError, "Kernels: table rows are not a tree over its joints");
        return NULL;
    }
    /* The sizes of one state (result_shape, work_size) fit MAX_DOUBLES each, so that no
     * entry's sum of them overflows. */
    Py_ssize_t size;
    if (checked_mul(rows, 6 * (Py_ssize_t)rows + WORK, MAX_DOUBLES, &size) < 0
            || checked_mul((Py_ssize_t)n, 10 * (Py_ssize_t)rows, MAX_DOUBLES, &size) < 0) {
        PyBuffer_Release(&v);
        PyErr_SetString(PyExc_ValueError, "Kernels: table too large");
        return NULL;
    }
    KernelsObject *self = (KernelsObject *)type->tp_alloc(type, 0);
    if (self == NULL) {
        PyBuffer_Release(&v);
        return NULL;
    }
    self->rows = rows;
    self->n = (long)n;
    self->nv = (long)K[VIDX];
    self->K = PyMem_Malloc(sizeof(double) * rows * WIDTH);
    self->zeros = PyMem_Calloc(self->nv + 1, sizeof(double));
    if (self->K != NULL)
        memcpy(self->K, K, sizeof(double) * rows * WIDTH);
    PyBuffer_Release(&v);
    if (self->K == NULL || self->zeros == NULL) {
        Py_DECREF(self);
        return PyErr_NoMemory();
    }
    return (PyObject *)self;
}

static PyMemberDef kernels_members[] = {
    {"n", T_LONG, offsetof(KernelsObject, n), READONLY, "number of joints (len(q))"},
    {"rows", T_LONG, offsetof(KernelsObject, rows), READONLY, "rows of the table (NB + 1)"},
    {"nv", T_LONG, offsetof(KernelsObject, nv), READONLY, "velocity coordinates (len(qd))"},
    {NULL},
};

static PyTypeObject KernelsType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "spatial_dynamics.backends._compiled.Kernels",
    .tp_doc = PyDoc_STR("Kernels(table): a model's table (backends/layout.py), copied once."),
    .tp_basicsize = sizeof(KernelsObject),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_new = kernels_new,
    .tp_dealloc = (destructor)kernels_dealloc,
    .tp_members = kernels_members,
};

/* ------------------------------------------------------------------------------------------
 * The algorithms: one row each, read by the generic entries below */

enum { RNEA = 0, CRBA = 1, MOMENTUM = 2, REGRESSOR = 3 };   /* the generated kernel it runs */

typedef struct {
    const char *name;       /* the single-state entry (and the door's kind: the row) */
    const char *batch;      /* the batch entry, or NULL */
    int vectors;            /* joint vectors it reads: q, then qd, then qdd (the rest zero) */
    int gravity;            /* 3 numbers after them */
    int fext;               /* then, optionally, the external forces (rnea's f_body) */
    int kernel;             /* results: RNEA tau (n,), CRBA H (n, n), MOMENTUM two (n,), */
                            /* REGRESSOR Y (n, 10 NB) */
    const char *outputs[2]; /* the batch entry's result arguments, as its errors name them */
    const char *doc, *batch_doc;
} Algorithm;

static const Algorithm ALGORITHMS[] = {
    {"rnea", "rnea_batch", 3, 1, 1, RNEA, {"tau"},
     "rnea(kernels, q, qd, qdd, gravity, f_body=None) -> tau (n,), or None\n\n"
     "One state: q, qd, qdd of n numbers each, gravity of 3 (m/s^2, root coordinates); f_body\n"
     "a C-contiguous float64 array of rows x 6 (the external force [n; f] on each body, body\n"
     "coordinates) or None. None when an argument is not such a state (the caller's general\n"
     "path takes it). float32 when q, qd and qdd all are (computed in float64).",
     "rnea_batch(kernels, N, q, qd, qdd, gravity, fext, tau, threads) -> None\n\n"
     "N states: q, qd, qdd C-contiguous float64 of N x n numbers, gravity 3 numbers, fext None\n"
     "or C-contiguous float64 of rows x 6 (shared) or N x rows x 6 numbers; writes tau (N x n).\n"
     "Releases the GIL; up to `threads` threads."},
    {"gravity_torque", NULL, 1, 1, 0, RNEA, {"tau"},
     "gravity_torque(kernels, q, gravity) -> g(q) (n,), or None: rnea at qd = qdd = 0.", NULL},
    {"bias_torque", NULL, 2, 1, 0, RNEA, {"tau"},
     "bias_torque(kernels, q, qd, gravity) -> C(q, qd) qd + g(q) (n,), or None: rnea at "
     "qdd = 0.", NULL},
    {"mass_matrix", "mass_matrix_batch", 1, 0, 0, CRBA, {"H"},
     "mass_matrix(kernels, q) -> M(q) (n, n), or None: the composite rigid body algorithm.",
     "mass_matrix_batch(kernels, N, q, H, threads) -> None: M(q) of N states into H "
     "(N x n x n)."},
    {"generalized_momentum", "momentum_batch", 2, 0, 0, MOMENTUM, {"mom", "ctq"},
     "generalized_momentum(kernels, q, qd) -> (M(q) qd, C(q, qd)^T qd), each (n,), or None.",
     "momentum_batch(kernels, N, q, qd, mom, ctq, threads) -> None: M(q) qd and C^T qd of N\n"
     "states into mom and ctq (N x n each)."},
    {"regressor", "regressor_batch", 3, 1, 0, REGRESSOR, {"Y"},
     "regressor(kernels, q, qd, qdd, gravity) -> Y (n, 10 NB), or None\n\n"
     "The joint-torque regressor of one state (tau = Y pi, pi the ten inertial parameters of\n"
     "each body); arguments as for rnea, None when one is not such a state.",
     "regressor_batch(kernels, N, q, qd, qdd, gravity, Y, threads) -> None: the regressors of\n"
     "N states (q, qd, qdd N x n each, gravity 3 numbers) into Y (N x n x 10 NB)."},
};
#define ALGORITHM_COUNT ((int)(sizeof ALGORITHMS / sizeof ALGORITHMS[0]))

static const char *const VECTOR_NAMES[3] = {"q", "qd", "qdd"};

/* The results of `kernel` for one state: how many (momentum's two, else one), their shape
 * dims[:ndim] (returned), and dims[0] x dims[1] doubles each. */
static int
result_shape(const KernelsObject *h, int kernel, npy_intp *dims, int *count)
{
    *count = kernel == MOMENTUM ? 2 : 1;
    dims[0] = h->nv;
    dims[1] = kernel == CRBA ? h->nv : (kernel == REGRESSOR ? 10 * (npy_intp)(h->rows - 1) : 1);
    return kernel == CRBA || kernel == REGRESSOR ? 2 : 1;
}

/* Scratch doubles of one state: the per-body rows, and the regressor's carried axes. */
static Py_ssize_t
work_size(int kernel, long rows)
{
    return (Py_ssize_t)rows * WORK
        + (kernel == REGRESSOR ? 6 * (Py_ssize_t)rows * ((Py_ssize_t)rows + 5) : 0);
}

/* One state through the generated kernels: the body transforms, then `kernel`'s passes.
 * g: 3 numbers; f: rows x 6 external forces or NULL; out2: momentum's second result. */
static void
run_state(int kernel, const double *K, long rows, const double *q, const double *qd,
          const double *qdd, const double *g, const double *f, double *out1, double *out2,
          double *work)
{
    xup_kernel(K, rows, q, work);
    switch (kernel) {
    case RNEA:
        rnea_kernel(K, rows, q, qd, qdd, g[0], g[1], g[2], f, f != NULL, out1, work);
        break;
    case CRBA:
        crba_kernel(K, rows, work, out1);
        break;
    case MOMENTUM:
        momentum_kernel(K, rows, q, qd, out1, out2, work);
        break;
    default:
        regressor_kernel(K, rows, qd, qdd, g[0], g[1], g[2], out1,
                         work + (Py_ssize_t)rows * WORK, work);
    }
}

/* ------------------------------------------------------------------------------------------
 * Arguments */

/* What as_doubles made of an argument: not one state it reads (the caller's general path
 * then decides), or the numbers, read from float32 or from anything else it reads. */
enum { DECLINED = 0, AS_DOUBLE = 1, AS_FLOAT = 2 };

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
 * one state of n numbers this entry reads; never an error. Read: a 1-D numpy array of
 * READ_TYPES in native byte order (any strides), a list or tuple of Python floats and ints,
 * another 1-D buffer of such items. */
static int
as_doubles(PyObject *obj, Py_ssize_t n, double *out)
{
    if (PyArray_Check(obj)) {
        PyArrayObject *a = (PyArrayObject *)obj;
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

static KernelsObject *
kernels_arg(PyObject *obj)
{
    if (!PyObject_TypeCheck(obj, &KernelsType)) {
        PyErr_Format(PyExc_TypeError, "expected Kernels, got %.100s", Py_TYPE(obj)->tp_name);
        return NULL;
    }
    return (KernelsObject *)obj;
}

/* Scratch of one call: `size` doubles on the stack (stack) or the heap. */
static double *
scratch(double *stack, Py_ssize_t size)
{
    if (size <= STACK_DOUBLES)
        return stack;
    double *p = PyMem_Malloc(sizeof(double) * size);
    if (p == NULL)
        PyErr_NoMemory();
    return p;
}

static void
scratch_free(double *p, double *stack)
{
    if (p != stack)
        PyMem_Free(p);
}

/* The buffer of obj, C-contiguous float64 (writable if asked); -1 with an error if not. */
static int
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

/* ------------------------------------------------------------------------------------------
 * One state: the entry of every algorithm */

/* args: kernels, the joint vectors, gravity (if the algorithm reads it), f_body (optional,
 * if it takes one). None when a vector or gravity is not one state that as_doubles reads.
 * The results are float32 when every joint vector is float32 (what numpy's promotion of
 * them gives), computed in float64 and rounded once; else float64. */
static PyObject *
single(const Algorithm *a, PyObject *const *args, Py_ssize_t nargs)
{
    const Py_ssize_t fixed = 1 + a->vectors + a->gravity;
    if (nargs != fixed && !(a->fext && nargs == fixed + 1)) {
        PyErr_Format(PyExc_TypeError,
                     a->fext ? "%s takes %zd or %zd arguments" : "%s takes %zd arguments",
                     a->name, fixed, fixed + 1);
        return NULL;
    }
    KernelsObject *h = kernels_arg(args[0]);
    if (h == NULL)
        return NULL;
    const Py_ssize_t n = h->n, rows = h->rows;
    npy_intp dims[2];
    int count;
    const int ndim = result_shape(h, a->kernel, dims, &count);
    const Py_ssize_t size = dims[0] * dims[1];
    /* Room for float32 results, computed in doubles first, only when q may be float32. */
    PyObject *q_arg = args[1];
    const int may_float = PyArray_Check(q_arg)
        ? PyArray_TYPE((PyArrayObject *)q_arg) == NPY_FLOAT
        : !(PyList_CheckExact(q_arg) || PyTuple_CheckExact(q_arg));
    double stack[STACK_DOUBLES];
    const Py_ssize_t nv = h->nv;
    double *buf = scratch(stack, n + 2 * nv + 3 + (may_float ? count * size : 0)
                                 + work_size(a->kernel, rows));
    if (buf == NULL)
        return NULL;
    double *x[3] = {buf, buf + n, buf + n + nv}, *g = buf + n + 2 * nv, *res = g + 3;
    double *work = res + (may_float ? count * size : 0);
    PyObject *results[2] = {NULL, NULL}, *out = NULL;
    Py_buffer fb = {0};
    const double *f = NULL;
    int floats = 0;         /* joint vectors read from float32 */
    for (int i = 0; i < a->vectors; i++) {
        const int read = as_doubles(args[1 + i], i == 0 ? n : nv, x[i]);
        if (read == DECLINED)
            goto declined;
        floats += read == AS_FLOAT;
    }
    for (int i = a->vectors; i < 3; i++)
        x[i] = h->zeros;
    if (a->gravity && !as_doubles(args[1 + a->vectors], 3, g))
        goto declined;
    if (nargs > fixed && args[fixed] != Py_None) {
        if (get_table(args[fixed], &fb, 0, "f_body") < 0)
            goto done;
        if (fb.len != (Py_ssize_t)sizeof(double) * rows * 6) {
            PyErr_SetString(PyExc_ValueError, "f_body must hold rows x 6 numbers");
            goto done;
        }
        f = fb.buf;
    }
    const int single_precision = may_float && floats == a->vectors;   /* res has room */
    double *data[2];
    for (int k = 0; k < count; k++) {
        results[k] = PyArray_SimpleNew(ndim, dims, single_precision ? NPY_FLOAT : NPY_DOUBLE);
        if (results[k] == NULL)
            goto done;
        data[k] = single_precision ? res + k * size
                                   : (double *)PyArray_DATA((PyArrayObject *)results[k]);
    }
    run_state(a->kernel, h->K, rows, x[0], x[1], x[2], g, f, data[0],
              count == 2 ? data[1] : NULL, work);
    for (int k = 0; single_precision && k < count; k++) {
        float *out32 = (float *)PyArray_DATA((PyArrayObject *)results[k]);
        for (Py_ssize_t i = 0; i < size; i++)
            out32[i] = (float)data[k][i];
    }
    if (count == 1) {
        out = results[0];       /* its reference */
        results[0] = NULL;
    } else {
        out = PyTuple_Pack(2, results[0], results[1]);
    }
    goto done;
declined:
    out = Py_None;
    Py_INCREF(out);
done:
    Py_XDECREF(results[0]);
    Py_XDECREF(results[1]);
    if (fb.obj != NULL)
        PyBuffer_Release(&fb);
    scratch_free(buf, stack);
    return out;
}

/* ------------------------------------------------------------------------------------------
 * Batches: the states claimed chunk by chunk by threads, without the GIL */

typedef struct {
    int kernel;
    const double *K;
    long rows, n, nv;                    /* q holds n numbers a state, qd and qdd nv */
    Py_ssize_t size;                     /* doubles of each result of one state */
    const double *q, *qd, *qdd, *fext;  /* (N, n) each or NULL; fext (1 or N, rows, 6) or NULL */
    int fext_per_state;
    double g[3];
    double *out1, *out2;                 /* tau | H | mom, ctq | Y */
} Slice;

#if !defined(_WIN32) && (defined(__GNUC__) || defined(__clang__))
#define THREADED 1
#define ATOMIC_ADD(p, x) __atomic_add_fetch((p), (x), __ATOMIC_ACQ_REL)
#else
#define ATOMIC_ADD(p, x) (*(p) += (x))     /* one thread: run_batch starts no other */
#endif

/* One batch as its threads share it: the states [0, N) claimed chunk by chunk. The caller
 * waits until every state is done, not for the threads: a thread that a busy machine starts
 * late finds nothing left and ends; the last thread out frees this. */
typedef struct {
    Slice job;
    Py_ssize_t N, chunk;
    Py_ssize_t next;                     /* the first state not claimed yet */
    Py_ssize_t done;                     /* states finished */
    int failed;                          /* chunks left undone (no memory for a scratch) */
    int refs;                            /* threads (the caller's included) holding this */
#ifdef THREADED
    pthread_mutex_t lock;
    pthread_cond_t finished;
#endif
} Batch;

/* The states [lo, hi) of job s with the scratch `work`: 0, or -1 without memory. */
static int
run_states(const Slice *s, double *work, Py_ssize_t lo, Py_ssize_t hi)
{
    const long n = s->n, nv = s->nv, rows = s->rows;
    if (work == NULL)
        return -1;
#ifdef SD_LANES
    if (s->kernel == RNEA && s->qd != NULL && s->qdd != NULL) {
        /* several states at once (SIMD across states), the same bits as one by one */
        const double *f = s->fext ? s->fext + (s->fext_per_state ? lo : 0) * rows * 6 : NULL;
        long done = rnea_batch_lanes(s->K, rows, (long)(hi - lo), s->q + lo * n,
                                     s->qd + lo * nv, s->qdd + lo * nv, s->g[0], s->g[1],
                                     s->g[2], f, s->fext_per_state, s->out1 + lo * s->size);
        if (done < 0)
            return -1;
        lo += done;
    }
#endif
    for (Py_ssize_t k = lo; k < hi; k++) {
        const double *f = s->fext ? s->fext + (s->fext_per_state ? k : 0) * rows * 6 : NULL;
        run_state(s->kernel, s->K, rows, s->q + k * n, s->qd ? s->qd + k * nv : NULL,
                  s->qdd ? s->qdd + k * nv : NULL, s->g, f, s->out1 + k * s->size,
                  s->out2 ? s->out2 + k * s->size : NULL, work);
    }
    return 0;
}

/* Claim chunks of b until none is left, and count them done (a chunk without memory too:
 * then b->failed). The thread that finishes the last state wakes the caller. */
static void
run_chunks(Batch *b)
{
    const Slice *s = &b->job;
    const long rows = s->rows;
    double *work = malloc(sizeof(double) * work_size(s->kernel, rows));
    for (;;) {
        Py_ssize_t lo = ATOMIC_ADD(&b->next, b->chunk) - b->chunk;
        if (lo >= b->N)
            break;
        Py_ssize_t hi = b->N - lo < b->chunk ? b->N : lo + b->chunk;
        if (run_states(s, work, lo, hi) < 0)
            ATOMIC_ADD(&b->failed, 1);
        if (ATOMIC_ADD(&b->done, hi - lo) == b->N) {
#ifdef THREADED
            pthread_mutex_lock(&b->lock);
            pthread_cond_broadcast(&b->finished);
            pthread_mutex_unlock(&b->lock);
#endif
        }
    }
    free(work);
}

/* Let go of b; the last thread frees it. */
static void
release_batch(Batch *b)
{
    if (ATOMIC_ADD(&b->refs, -1) == 0) {
#ifdef THREADED
        pthread_mutex_destroy(&b->lock);
        pthread_cond_destroy(&b->finished);
#endif
        free(b);
    }
}

#ifdef THREADED
static void *
run_thread(void *arg)
{
    run_chunks((Batch *)arg);
    release_batch((Batch *)arg);
    return NULL;
}
#endif

/* Run states [0, N) of `job` on up to `threads` threads (the caller's included). */
static int
run_batch(const Slice *job, Py_ssize_t N, long threads)
{
    long T = threads < 1 ? 1 : (threads > MAX_THREADS ? MAX_THREADS : threads);
    Py_ssize_t most = N * job->rows / MIN_WORK;
    if (T > most)
        T = most > 0 ? (long)most : 1;
    Batch *b = calloc(1, sizeof(Batch));
    if (b == NULL) {
        PyErr_NoMemory();
        return -1;
    }
    b->job = *job;
    b->N = N;
    b->chunk = (CHUNK_WORK / job->rows + 7) / 8 * 8;
    if (b->chunk < 8)
        b->chunk = 8;
    b->refs = 1;
    int failed;
    Py_BEGIN_ALLOW_THREADS
#ifdef THREADED
    pthread_mutex_init(&b->lock, NULL);
    pthread_cond_init(&b->finished, NULL);
    pthread_attr_t attr;
    int detached = T > 1 && pthread_attr_init(&attr) == 0;
    if (detached && pthread_attr_setdetachstate(&attr, PTHREAD_CREATE_DETACHED) != 0) {
        pthread_attr_destroy(&attr);
        detached = 0;
    }
    for (long t = 1; detached && t < T; t++) {
        pthread_t id;
        ATOMIC_ADD(&b->refs, 1);
        if (pthread_create(&id, &attr, run_thread, b) != 0) {
            ATOMIC_ADD(&b->refs, -1);   /* no thread to be had: the others take its part */
            break;
        }
    }
    if (detached)
        pthread_attr_destroy(&attr);
#endif
    run_chunks(b);
#ifdef THREADED
    pthread_mutex_lock(&b->lock);
    while (__atomic_load_n(&b->done, __ATOMIC_ACQUIRE) < N)
        pthread_cond_wait(&b->finished, &b->lock);
    pthread_mutex_unlock(&b->lock);
#endif
    failed = b->failed;
    release_batch(b);
    Py_END_ALLOW_THREADS
    if (failed) {
        PyErr_NoMemory();
        return -1;
    }
    return 0;
}

/* args: kernels, N, the joint vectors (C-contiguous float64, N x n each), gravity (if the
 * algorithm reads it), fext (if it takes one: None, or C-contiguous float64 of rows x 6 or
 * N x rows x 6), the results (C-contiguous float64, writable), threads. */
static PyObject *
batch(const Algorithm *a, PyObject *const *args, Py_ssize_t nargs)
{
    npy_intp dims[2];
    int count;
    const Py_ssize_t want = 3 + a->vectors + a->gravity + a->fext + (a->kernel == MOMENTUM);
    if (nargs != want + 1) {
        PyErr_Format(PyExc_TypeError, "%s takes %zd arguments", a->batch, want + 1);
        return NULL;
    }
    KernelsObject *h = kernels_arg(args[0]);
    Py_ssize_t N = PyLong_AsSsize_t(args[1]);
    long threads = PyLong_AsLong(args[want]);
    if (h == NULL || PyErr_Occurred())
        return NULL;
    /* N states of `rows` bodies each: the chunks and threads count body-states (run_batch) */
    Py_ssize_t body_states;
    if (checked_mul(N, h->rows * 6, MAX_DOUBLES, &body_states) < 0) {
        PyErr_Format(PyExc_ValueError, "%s: N must be 0 to %zd states, got %zd", a->batch,
                     MAX_DOUBLES / (h->rows * 6), N);
        return NULL;
    }
    result_shape(h, a->kernel, dims, &count);
    Slice job = {.kernel = a->kernel, .K = h->K, .rows = h->rows, .n = h->n, .nv = h->nv,
                 .size = dims[0] * dims[1]};
    Py_ssize_t next = 2 + a->vectors;
    if (a->gravity && !as_doubles(args[next++], 3, job.g)) {
        PyErr_SetString(PyExc_TypeError, "gravity must be 3 numbers");
        return NULL;
    }
    PyObject *fext = a->fext ? args[next++] : Py_None;
    /* the buffers: the joint vectors, the results, then the external forces */
    Py_buffer v[6];
    int held = 0;
    for (int i = 0; i < a->vectors + count; i++, held++) {
        const int result = i >= a->vectors;
        const char *name = result ? a->outputs[i - a->vectors] : VECTOR_NAMES[i];
        const Py_ssize_t per_state = result ? job.size : (i == 0 ? h->n : h->nv);
        Py_ssize_t numbers;     /* -1: more than any buffer holds */
        if (checked_mul(N, per_state, PY_SSIZE_T_MAX / 8, &numbers) < 0)
            numbers = -1;
        if (get_table(result ? args[next + i - a->vectors] : args[2 + i], &v[i], result,
                      name) < 0)
            goto fail;
        if (v[i].len % (Py_ssize_t)sizeof(double) != 0
                || v[i].len / (Py_ssize_t)sizeof(double) != numbers) {
            PyBuffer_Release(&v[i]);
            if (numbers >= 0)
                PyErr_Format(PyExc_ValueError, "%s must hold %zd numbers", name, numbers);
            else
                PyErr_Format(PyExc_ValueError, "%s must hold %zd x %zd numbers", name, N,
                             per_state);
            goto fail;
        }
    }
    if (fext != Py_None) {
        if (get_table(fext, &v[held], 0, "fext") < 0)
            goto fail;
        Py_ssize_t m = v[held++].len / (Py_ssize_t)sizeof(double);
        if (v[held - 1].len % (Py_ssize_t)sizeof(double) != 0
                || (m != h->rows * 6 && m != body_states)) {
            PyErr_SetString(PyExc_ValueError, "fext must hold rows x 6 or N x rows x 6 numbers");
            goto fail;
        }
        job.fext = v[held - 1].buf;
        job.fext_per_state = m != h->rows * 6;
    }
    const double **vectors[3] = {&job.q, &job.qd, &job.qdd};
    for (int i = 0; i < a->vectors; i++)
        *vectors[i] = v[i].buf;
    job.out1 = v[a->vectors].buf;
    job.out2 = count == 2 ? v[a->vectors + 1].buf : NULL;
    /* no state, or states without results (a model without joints): nothing to compute */
    int rc = N == 0 || job.size == 0 ? 0 : run_batch(&job, N, threads);
    for (int i = 0; i < held; i++)
        PyBuffer_Release(&v[i]);
    if (rc < 0)
        return NULL;
    Py_RETURN_NONE;
fail:
    for (int i = 0; i < held; i++)
        PyBuffer_Release(&v[i]);
    return NULL;
}

/* The module's functions: `self` is the index of their row in ALGORITHMS (PyInit). */
static PyObject *
c_single(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    return single(&ALGORITHMS[PyLong_AsLong(self)], args, nargs);
}

static PyObject *
c_batch(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    return batch(&ALGORITHMS[PyLong_AsLong(self)], args, nargs);
}

/* ------------------------------------------------------------------------------------------
 * Door: a public function of spatial_dynamics entered in C
 *
 * Door(function, kind, kernels, gravity) is called as `function` is (same arguments, and it
 * carries its __doc__, __name__ and __wrapped__); `kind` is the row of `function` in
 * ALGORITHMS (the module's ALGORITHMS names them in order). One state with gravity given or
 * default (`gravity` when not given), no f_ext and backend 'auto' or 'compiled', of a model
 * whose Kernels are in the dict `kernels` (id(model) -> Kernels), runs here; every other
 * call, or one whose arguments the entry declines, is passed on to `function` unchanged (it
 * validates, derives the table, runs batches and the other backends). This saves the Python
 * frame of `function` (~0.2 µs, a fifth of a call) on the path users take most. The door
 * keeps the last model it answered (a weak reference) and its Kernels, so that a run of
 * calls on one model skips the dict; when that model is collected, the weak reference's
 * callback lets go of its Kernels. */

static PyObject *str_gravity, *str_f_ext, *str_backend, *str_auto, *str_compiled;

typedef struct {
    PyObject_HEAD
    vectorcallfunc vectorcall;
    int kind;
    PyObject *function;   /* the Python function: every other call */
    PyObject *kernels;    /* dict id(model) -> Kernels */
    PyObject *gravity;    /* the default gravity */
    PyObject *dict;       /* __doc__, __name__, __wrapped__, … */
    PyObject *last_model; /* a weak reference to the model of the last call, or NULL */
    PyObject *last_kern;  /* its Kernels (NULL once the model was collected) */
} DoorObject;

/* Whether the model of the last call is `model`, alive (its Kernels are still in the dict,
 * removed only when the model is collected). Saves the dict look-up (~40 ns) of each call
 * on one model. A dead reference is never the model: before Python 3.13 it reads as None,
 * which a caller may well pass. */
static int
door_is_last(DoorObject *self, PyObject *model)
{
    if (self->last_model == NULL)
        return 0;
#if PY_VERSION_HEX >= 0x030D0000
    PyObject *obj;
    if (PyWeakref_GetRef(self->last_model, &obj) <= 0) {
        PyErr_Clear();
        return 0;
    }
    Py_DECREF(obj);
    return obj == model;
#else
    PyObject *obj = PyWeakref_GET_OBJECT(self->last_model);
    return obj != Py_None && obj == model;
#endif
}

/* The callback of the weak reference to the last model (`door` the door): the model was
 * collected, let go of its Kernels. The dead reference itself stays until the next model
 * (door_is_last never takes it for one): it is the argument of this very call. */
static PyObject *
door_forget(PyObject *door, PyObject *ref)
{
    DoorObject *self = (DoorObject *)door;
    if (self->last_model == ref)
        Py_CLEAR(self->last_kern);
    Py_RETURN_NONE;
}

static PyMethodDef door_forget_def = {"forget", door_forget, METH_O, NULL};

static int
is_name(PyObject *name, PyObject *interned)
{
    return name == interned || PyUnicode_Compare(name, interned) == 0;
}

static PyObject *
door_call(DoorObject *self, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    Py_ssize_t nargs = PyVectorcall_NARGS(nargsf);
    const Algorithm *a = &ALGORITHMS[self->kind];
    const int nv = a->vectors;
    PyObject *gravity = self->gravity, *f_ext = NULL, *backend = NULL;
    Py_ssize_t nkw = kwnames ? PyTuple_GET_SIZE(kwnames) : 0;
    int ok = nargs >= 1 + nv;
    /* optional arguments by position: gravity, f_ext, backend (those the function has) */
    Py_ssize_t k = 1 + nv;
    int given_gravity = ok && a->gravity && k < nargs;
    if (given_gravity)
        gravity = args[k++];
    if (ok && a->fext && k < nargs)
        f_ext = args[k++];
    if (ok && k < nargs)
        backend = args[k++];
    ok = ok && k == nargs;
    /* then by keyword; one given twice (by position too) is the function's TypeError */
    for (Py_ssize_t i = 0; ok && i < nkw; i++) {
        PyObject *name = PyTuple_GET_ITEM(kwnames, i), *value = args[nargs + i];
        if (a->gravity && is_name(name, str_gravity)) {
            ok = !given_gravity;
            given_gravity = 1;
            gravity = value;
        } else if (a->fext && is_name(name, str_f_ext)) {
            ok = f_ext == NULL;
            f_ext = value;
        } else if (is_name(name, str_backend)) {
            ok = backend == NULL;
            backend = value;
        } else {
            ok = 0;
        }
    }
    if (ok && f_ext != NULL && f_ext != Py_None)
        ok = PyDict_CheckExact(f_ext) && PyDict_GET_SIZE(f_ext) == 0;
    if (ok && backend != NULL)
        ok = PyUnicode_CheckExact(backend)
             && (is_name(backend, str_auto) || is_name(backend, str_compiled));
    PyObject *kern = NULL;
    if (ok && door_is_last(self, args[0])) {
        kern = self->last_kern;
    } else if (ok) {
        PyObject *key = PyLong_FromVoidPtr(args[0]);
        if (key == NULL)
            return NULL;
        kern = PyDict_GetItemWithError(self->kernels, key);   /* borrowed */
        Py_DECREF(key);
        if (kern == NULL && PyErr_Occurred())
            return NULL;
        ok = kern != NULL && PyObject_TypeCheck(kern, &KernelsType);
        if (ok) {
            PyObject *forget = PyCFunction_New(&door_forget_def, (PyObject *)self);
            PyObject *ref = forget ? PyWeakref_NewRef(args[0], forget) : NULL;
            Py_XDECREF(forget);     /* the reference holds it */
            if (ref == NULL) {
                PyErr_Clear();      /* no weak references to it: no cache */
            } else {
                Py_INCREF(kern);
                Py_XSETREF(self->last_kern, kern);
                Py_XSETREF(self->last_model, ref);
            }
        }
    }
    if (ok) {
        Py_INCREF(kern);
        /* kernels, the joint vectors, gravity (read when the algorithm takes it) */
        PyObject *call[5] = {kern, args[1], nv > 1 ? args[2] : NULL, nv > 2 ? args[3] : NULL};
        call[1 + nv] = gravity;
        PyObject *out = single(a, call, 1 + nv + a->gravity);
        Py_DECREF(kern);
        if (out != Py_None)
            return out;        /* the answer, or an error (no memory) */
        Py_DECREF(out);
    }
    return PyObject_Vectorcall(self->function, args, nargsf, kwnames);
}

static PyObject *
door_new(PyTypeObject *type, PyObject *args, PyObject *kwds)
{
    PyObject *function, *kernels, *gravity;
    int kind;
    static char *keywords[] = {"function", "kind", "kernels", "gravity", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "OiO!O:Door", keywords, &function, &kind,
                                     &PyDict_Type, &kernels, &gravity))
        return NULL;
    if (kind < 0 || kind >= ALGORITHM_COUNT || !PyCallable_Check(function)) {
        PyErr_Format(PyExc_ValueError, "Door: a callable and a kind in 0..%d",
                     ALGORITHM_COUNT - 1);
        return NULL;
    }
    DoorObject *self = (DoorObject *)type->tp_alloc(type, 0);
    if (self == NULL)
        return NULL;
    self->vectorcall = (vectorcallfunc)door_call;
    self->kind = kind;
    Py_INCREF(function);
    self->function = function;
    Py_INCREF(kernels);
    self->kernels = kernels;
    Py_INCREF(gravity);
    self->gravity = gravity;
    return (PyObject *)self;
}

/* Each reference a door holds, through `DO` (Py_VISIT for the collector, Py_CLEAR). */
#define DOOR_REFERENCES(DO)                                                           \
    do {                                                                              \
        DO(self->function);                                                           \
        DO(self->kernels);                                                            \
        DO(self->gravity);                                                            \
        DO(self->dict);                                                               \
        DO(self->last_model);                                                         \
        DO(self->last_kern);                                                          \
    } while (0)

static int
door_traverse(DoorObject *self, visitproc visit, void *arg)
{
    DOOR_REFERENCES(Py_VISIT);
    return 0;
}

static int
door_clear(DoorObject *self)
{
    DOOR_REFERENCES(Py_CLEAR);
    return 0;
}

static void
door_dealloc(DoorObject *self)
{
    PyObject_GC_UnTrack(self);
    door_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *
door_repr(DoorObject *self)
{
    return PyUnicode_FromFormat("<compiled door to %R>", self->function);
}

/* Pickled (and copied) by name, as functions are: the name of `function` in its module
 * (`__module__`, which the door carries), where the door stands in for it; loading finds
 * the door, or the plain function in a package built without the extension. */
static PyObject *
door_reduce(DoorObject *self, PyObject *Py_UNUSED(ignored))
{
    return PyObject_GetAttrString(self->function, "__qualname__");
}

static PyMethodDef door_methods[] = {
    {"__reduce__", (PyCFunction)door_reduce, METH_NOARGS,
     PyDoc_STR("The function's name: pickled and copied as the function is.")},
    {NULL},
};

static PyGetSetDef door_getset[] = {
    {"__dict__", PyObject_GenericGetDict, PyObject_GenericSetDict, NULL, NULL},
    {NULL},
};

static PyTypeObject DoorType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "spatial_dynamics.backends._compiled.Door",
    .tp_doc = PyDoc_STR("Door(function, kind, kernels, gravity): `function`, one state in C."),
    .tp_basicsize = sizeof(DoorObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_new = door_new,
    .tp_dealloc = (destructor)door_dealloc,
    .tp_traverse = (traverseproc)door_traverse,
    .tp_clear = (inquiry)door_clear,
    .tp_repr = (reprfunc)door_repr,
    .tp_call = PyVectorcall_Call,
    .tp_vectorcall_offset = offsetof(DoorObject, vectorcall),
    .tp_dictoffset = offsetof(DoorObject, dict),
    .tp_getset = door_getset,
    .tp_methods = door_methods,
};

/* ------------------------------------------------------------------------------------------
 * The module */

/* The functions' definitions, two a row of ALGORITHMS (single state, batch), filled in by
 * PyInit; each function's `self` is its row's index, which c_single and c_batch read. */
static PyMethodDef entries[2 * ALGORITHM_COUNT];

/* Add the entries of ALGORITHMS to m, and ALGORITHMS: their names in order (the doors'
 * kinds). */
static int
add_entries(PyObject *m)
{
    PyObject *names = PyTuple_New(ALGORITHM_COUNT), *module = PyModule_GetNameObject(m);
    int ok = names != NULL && module != NULL;
    for (int i = 0; ok && i < ALGORITHM_COUNT; i++) {
        const Algorithm *a = &ALGORITHMS[i];
        entries[2 * i] = (PyMethodDef){a->name, (PyCFunction)(void (*)(void))c_single,
                                       METH_FASTCALL, a->doc};
        entries[2 * i + 1] = (PyMethodDef){a->batch, (PyCFunction)(void (*)(void))c_batch,
                                           METH_FASTCALL, a->batch_doc};
        PyObject *index = PyLong_FromLong(i), *name = PyUnicode_FromString(a->name);
        ok = index != NULL && name != NULL;
        PyTuple_SET_ITEM(names, i, name);       /* NULL until ok: then names is dropped */
        for (int e = 2 * i; ok && e < 2 * i + (a->batch ? 2 : 1); e++) {
            PyObject *f = PyCFunction_NewEx(&entries[e], index, module);
            ok = f != NULL && PyModule_AddObject(m, entries[e].ml_name, f) == 0;
            if (!ok)
                Py_XDECREF(f);
        }
        Py_XDECREF(index);
    }
    ok = ok && PyModule_AddObject(m, "ALGORITHMS", names) == 0;
    if (!ok)
        Py_XDECREF(names);
    Py_XDECREF(module);
    return ok ? 0 : -1;
}

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT,
    .m_name = "spatial_dynamics.backends._compiled",
    .m_doc = PyDoc_STR("The generated kernels, compiled when the package is built."),
    .m_size = -1,
};

PyMODINIT_FUNC
PyInit__compiled(void)
{
    import_array();
    if (PyType_Ready(&KernelsType) < 0 || PyType_Ready(&DoorType) < 0)
        return NULL;
    str_gravity = PyUnicode_InternFromString("gravity");
    str_f_ext = PyUnicode_InternFromString("f_ext");
    str_backend = PyUnicode_InternFromString("backend");
    str_auto = PyUnicode_InternFromString("auto");
    str_compiled = PyUnicode_InternFromString("compiled");
    if (!(str_gravity && str_f_ext && str_backend && str_auto && str_compiled))
        return NULL;
    PyObject *m = PyModule_Create(&module_def);
    if (m == NULL)
        return NULL;
    Py_INCREF(&KernelsType);
    Py_INCREF(&DoorType);
    if (PyModule_AddObject(m, "Kernels", (PyObject *)&KernelsType) < 0
            || PyModule_AddObject(m, "Door", (PyObject *)&DoorType) < 0
            || add_entries(m) < 0
            || PyModule_AddIntConstant(m, "API", API) < 0
            || PyModule_AddStringConstant(m, "KERNELS_SHA256", KERNELS_SHA256) < 0
            || PyModule_AddIntConstant(m, "WORK", WORK) < 0
            || PyModule_AddIntConstant(m, "MAX_THREADS", MAX_THREADS) < 0
            || PyModule_AddIntConstant(m, "MIN_WORK", MIN_WORK) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}

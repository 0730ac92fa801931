/* Copyright 2026 spatial_dynamics contributors
 * SPDX-License-Identifier: Apache-2.0
 *
 * spatial_dynamics.backends._compiled: the kernels of _kernels_generated.h (generated from
 * spatial_dynamics/algorithms by codegen.py) as a CPython extension, built by setup.py.
 *
 * This file only moves data. A Kernels object holds a copy of a model's table (the rows of
 * backends/layout.py, prepared once in Python). The single-state entries (METH_FASTCALL)
 * read q, qd, qdd and gravity once each into C doubles: a 1-D numpy array of float64 or
 * integers (any strides) through the numpy C API, a list or tuple of Python floats and
 * ints, or another 1-D buffer of such numbers through the buffer protocol; anything else (a
 * batch, float32, a wrong length, other objects) returns None so that the Python caller
 * takes its general path, which validates and names the argument. Results are new numpy
 * arrays. The batch entries take C-contiguous float64 arrays prepared by the caller, release
 * the GIL and let POSIX threads claim the states chunk by chunk; the RNEA of a batch runs
 * several states at once in the SIMD lanes of _kernels_generated.h.
 *
 * The numpy C API, version-targeted: built against numpy 2.x headers, the extension also
 * runs on numpy 1.23 and later (NPY_TARGET_VERSION; 1.23 is the oldest numpy for Python
 * 3.11), e.g. Ubuntu 24.04's 1.26. Built against numpy 1.x headers it runs on numpy 1.x
 * only (numpy's rule); import_array then fails on 2.x and the package runs on plain Python,
 * with compiled.py's warning.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

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
#define API 2
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

/* ------------------------------------------------------------------------------------------
 * Kernels: one model's table */

typedef struct {
    PyObject_HEAD
    double *K;          /* rows x WIDTH, row-major */
    long rows;          /* NB + 1 */
    long n;             /* joints (len(q)) */
    double *zeros;      /* n zeros: qd, qdd of the terms at rest */
    npy_intp nn[2];     /* (n, n) and (n, 10 NB): the shapes of the results */
    npy_intp ny[2];
} KernelsObject;

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
    int ok = n >= 0.0 && n <= 1e9 && n == (double)(long)n;
    /* The kernels index q, the scratch and their parents by these columns: check them once,
     * so no table reaches the kernels that could make them read or write out of bounds. */
    for (long i = 1; ok && i < rows; i++) {
        const double *row = K + i * WIDTH;
        ok = row[0] >= 0.0 && row[0] < (double)i && row[0] == (double)(long)row[0]
             && row[1] >= 0.0 && row[1] <= (double)PR && row[1] == (double)(long)row[1]
             && row[QIDX] >= 0.0 && row[QIDX] < n && row[QIDX] == (double)(long)row[QIDX];
    }
    if (!ok) {
        PyBuffer_Release(&v);
        PyErr_SetString(PyExc_ValueError, "Kernels: table rows are not a tree over its joints");
        return NULL;
    }
    KernelsObject *self = (KernelsObject *)type->tp_alloc(type, 0);
    if (self == NULL) {
        PyBuffer_Release(&v);
        return NULL;
    }
    self->rows = rows;
    self->n = (long)n;
    self->K = PyMem_Malloc(sizeof(double) * rows * WIDTH);
    self->zeros = PyMem_Calloc(self->n + 1, sizeof(double));
    if (self->K != NULL)
        memcpy(self->K, K, sizeof(double) * rows * WIDTH);
    PyBuffer_Release(&v);
    self->nn[0] = self->nn[1] = self->ny[0] = self->n;
    self->ny[1] = 10 * (rows - 1);
    if (self->K == NULL || self->zeros == NULL) {
        Py_DECREF(self);
        return PyErr_NoMemory();
    }
    return (PyObject *)self;
}

static PyObject *
kernels_get_n(KernelsObject *self, void *closure)
{
    return PyLong_FromLong(self->n);
}

static PyObject *
kernels_get_rows(KernelsObject *self, void *closure)
{
    return PyLong_FromLong(self->rows);
}

static PyGetSetDef kernels_getset[] = {
    {"n", (getter)kernels_get_n, NULL, "number of joints (len(q))", NULL},
    {"rows", (getter)kernels_get_rows, NULL, "rows of the table (NB + 1)", NULL},
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
    .tp_getset = kernels_getset,
};

/* ------------------------------------------------------------------------------------------
 * Arguments */

/* Read the 1-D buffer v (n items, any strides) as doubles: 1, or 0 for an item type this
 * entry leaves to the general path (float32, float16, longdouble, complex, objects, …). */
static int
read_buffer(const Py_buffer *v, double *out)
{
    const char *fmt = v->format ? v->format : "B";
#if PY_LITTLE_ENDIAN
    if (*fmt == '@' || *fmt == '=' || *fmt == '<')
#else
    if (*fmt == '@' || *fmt == '=' || *fmt == '>' || *fmt == '!')
#endif
        fmt++;
    if (fmt[0] == '\0' || fmt[1] != '\0')
        return 0;
    const char *p = (const char *)v->buf;
    Py_ssize_t n = v->shape[0], step = v->strides[0];
#define READ(ctype)                                                                 \
    do {                                                                            \
        if (v->itemsize != (Py_ssize_t)sizeof(ctype))                               \
            return 0;                                                               \
        for (Py_ssize_t i = 0; i < n; i++) {                                        \
            ctype x;                                                                \
            memcpy(&x, p + i * step, sizeof x);                                     \
            out[i] = (double)x;                                                     \
        }                                                                           \
        return 1;                                                                   \
    } while (0)
    switch (fmt[0]) {
    case 'd': READ(double);
    case '?': READ(unsigned char);
    case 'b': READ(signed char);
    case 'B': READ(unsigned char);
    case 'h': READ(short);
    case 'H': READ(unsigned short);
    case 'i': READ(int);
    case 'I': READ(unsigned int);
    case 'l': READ(long);
    case 'L': READ(unsigned long);
    case 'q': READ(long long);
    case 'Q': READ(unsigned long long);
    default: return 0;
    }
#undef READ
}

/* The 1-D numpy array a of n items as doubles: 1, or 0 for an item type or byte order the
 * buffer protocol path would decline too (read_buffer: float32, float16, longdouble,
 * complex, objects, datetimes, swapped bytes, …), so both paths take the same arrays. */
static int
read_array(PyArrayObject *a, Py_ssize_t n, double *out)
{
    const char *p = PyArray_BYTES(a);
    const npy_intp step = PyArray_STRIDE(a, 0);
    if (!PyArray_ISNOTSWAPPED(a))
        return 0;
#define READ(ctype)                                                                 \
    do {                                                                            \
        for (Py_ssize_t i = 0; i < n; i++) {                                        \
            ctype x;                                                                \
            memcpy(&x, p + i * step, sizeof x);                                     \
            out[i] = (double)x;                                                     \
        }                                                                           \
        return 1;                                                                   \
    } while (0)
    switch (PyArray_TYPE(a)) {
    case NPY_DOUBLE:
        if (step == (npy_intp)sizeof(double)) {     /* contiguous: the common case */
            memcpy(out, p, sizeof(double) * n);
            return 1;
        }
        READ(double);
    case NPY_BOOL: READ(npy_bool);
    case NPY_BYTE: READ(npy_byte);
    case NPY_UBYTE: READ(npy_ubyte);
    case NPY_SHORT: READ(npy_short);
    case NPY_USHORT: READ(npy_ushort);
    case NPY_INT: READ(npy_int);
    case NPY_UINT: READ(npy_uint);
    case NPY_LONG: READ(npy_long);
    case NPY_ULONG: READ(npy_ulong);
    case NPY_LONGLONG: READ(npy_longlong);
    case NPY_ULONGLONG: READ(npy_ulonglong);
    default: return 0;
    }
#undef READ
}

/* ``obj`` as n doubles: 1; 0 when it is not one state of n numbers this entry reads (the
 * caller's general path then decides); never an error. */
static int
as_doubles(PyObject *obj, Py_ssize_t n, double *out)
{
    if (PyArray_Check(obj)) {
        PyArrayObject *a = (PyArrayObject *)obj;
        return PyArray_NDIM(a) == 1 && PyArray_DIM(a, 0) == n && read_array(a, n, out);
    }
    if (PyList_CheckExact(obj) || PyTuple_CheckExact(obj)) {
        if (PySequence_Fast_GET_SIZE(obj) != n)
            return 0;
        PyObject **items = PySequence_Fast_ITEMS(obj);
        for (Py_ssize_t i = 0; i < n; i++) {
            PyObject *x = items[i];
            if (PyFloat_Check(x)) {
                out[i] = PyFloat_AS_DOUBLE(x);
            } else if (PyLong_Check(x)) {
                out[i] = PyLong_AsDouble(x);
                if (out[i] == -1.0 && PyErr_Occurred()) {
                    PyErr_Clear();
                    return 0;
                }
            } else {
                return 0;
            }
        }
        return 1;
    }
    if (PyBytes_Check(obj) || PyByteArray_Check(obj) || !PyObject_CheckBuffer(obj))
        return 0;
    Py_buffer v;
    if (PyObject_GetBuffer(obj, &v, PyBUF_STRIDES | PyBUF_FORMAT) < 0) {
        PyErr_Clear();
        return 0;
    }
    int ok = v.ndim == 1 && v.shape[0] == n && read_buffer(&v, out);
    PyBuffer_Release(&v);
    return ok;
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

/* A new C-contiguous float64 array of shape dims[:ndim] (what numpy.empty makes), and its
 * data in *data. */
static PyObject *
new_array(int ndim, npy_intp *dims, double **data)
{
    PyObject *out = PyArray_SimpleNew(ndim, dims, NPY_DOUBLE);
    if (out != NULL)
        *data = (double *)PyArray_DATA((PyArrayObject *)out);
    return out;
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
 * Single states */

PyDoc_STRVAR(rnea_doc,
"rnea(kernels, q, qd, qdd, gravity, f_body=None) -> tau (n,), or None\n\n"
"One state: q, qd, qdd of n numbers each, gravity of 3 (m/s^2, root coordinates); f_body\n"
"a C-contiguous float64 array of rows x 6 (the external force [n; f] on each body, body\n"
"coordinates) or None. None when an argument is not such a state (the caller's general\n"
"path takes it).");

static PyObject *
c_rnea(PyObject *module, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 5 && nargs != 6) {
        PyErr_SetString(PyExc_TypeError, "rnea takes 5 or 6 arguments");
        return NULL;
    }
    KernelsObject *h = kernels_arg(args[0]);
    if (h == NULL)
        return NULL;
    const Py_ssize_t n = h->n, rows = h->rows;
    double stack[STACK_DOUBLES];
    double *buf = scratch(stack, 3 * n + 3 + rows * WORK);
    if (buf == NULL)
        return NULL;
    double *q = buf, *qd = q + n, *qdd = qd + n, *g = qdd + n, *work = g + 3;
    PyObject *out = NULL;
    Py_buffer fb = {0};
    double *tau;
    int has_fext = nargs == 6 && args[5] != Py_None;
    if (!(as_doubles(args[1], n, q) && as_doubles(args[2], n, qd)
          && as_doubles(args[3], n, qdd) && as_doubles(args[4], 3, g))) {
        out = Py_None;
        Py_INCREF(out);
        goto done;
    }
    if (has_fext) {
        if (get_table(args[5], &fb, 0, "f_body") < 0)
            goto done;
        if (fb.len != (Py_ssize_t)sizeof(double) * rows * 6) {
            PyErr_SetString(PyExc_ValueError, "f_body must hold rows x 6 numbers");
            goto done;
        }
    }
    out = new_array(1, h->nn, &tau);
    if (out == NULL)
        goto done;
    xup_kernel(h->K, rows, q, work);
    rnea_kernel(h->K, rows, q, qd, qdd, g[0], g[1], g[2],
                has_fext ? (const double *)fb.buf : NULL, has_fext, tau, work);
done:
    if (has_fext && fb.obj != NULL)
        PyBuffer_Release(&fb);
    scratch_free(buf, stack);
    return out;
}

/* RNEA with qd, qdd given or zero: the shared body of gravity_torque and bias_torque. */
static PyObject *
rnea_at_rest(PyObject *const *args, Py_ssize_t nargs, int with_qd, const char *name)
{
    if (nargs != (with_qd ? 4 : 3)) {
        PyErr_Format(PyExc_TypeError, "%s takes %d arguments", name, with_qd ? 4 : 3);
        return NULL;
    }
    KernelsObject *h = kernels_arg(args[0]);
    if (h == NULL)
        return NULL;
    const Py_ssize_t n = h->n, rows = h->rows;
    double stack[STACK_DOUBLES];
    double *buf = scratch(stack, 2 * n + 3 + rows * WORK);
    if (buf == NULL)
        return NULL;
    double *q = buf, *qd = q + n, *g = qd + n, *work = g + 3;
    PyObject *out = NULL;
    double *tau;
    if (!(as_doubles(args[1], n, q) && (!with_qd || as_doubles(args[2], n, qd))
          && as_doubles(args[with_qd ? 3 : 2], 3, g))) {
        out = Py_None;
        Py_INCREF(out);
    } else if ((out = new_array(1, h->nn, &tau)) != NULL) {
        xup_kernel(h->K, rows, q, work);
        rnea_kernel(h->K, rows, q, with_qd ? qd : h->zeros, h->zeros, g[0], g[1], g[2], NULL,
                    0, tau, work);
    }
    scratch_free(buf, stack);
    return out;
}

PyDoc_STRVAR(gravity_torque_doc,
"gravity_torque(kernels, q, gravity) -> g(q) (n,), or None: rnea at qd = qdd = 0.");

static PyObject *
c_gravity_torque(PyObject *module, PyObject *const *args, Py_ssize_t nargs)
{
    return rnea_at_rest(args, nargs, 0, "gravity_torque");
}

PyDoc_STRVAR(bias_torque_doc,
"bias_torque(kernels, q, qd, gravity) -> C(q, qd) qd + g(q) (n,), or None: rnea at qdd = 0.");

static PyObject *
c_bias_torque(PyObject *module, PyObject *const *args, Py_ssize_t nargs)
{
    return rnea_at_rest(args, nargs, 1, "bias_torque");
}

PyDoc_STRVAR(mass_matrix_doc,
"mass_matrix(kernels, q) -> M(q) (n, n), or None: the composite rigid body algorithm.");

static PyObject *
c_mass_matrix(PyObject *module, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 2) {
        PyErr_SetString(PyExc_TypeError, "mass_matrix takes 2 arguments");
        return NULL;
    }
    KernelsObject *h = kernels_arg(args[0]);
    if (h == NULL)
        return NULL;
    const Py_ssize_t n = h->n, rows = h->rows;
    double stack[STACK_DOUBLES];
    double *buf = scratch(stack, n + rows * WORK);
    if (buf == NULL)
        return NULL;
    double *q = buf, *work = q + n;
    PyObject *out = NULL;
    double *H;
    if (!as_doubles(args[1], n, q)) {
        out = Py_None;
        Py_INCREF(out);
    } else if ((out = new_array(2, h->nn, &H)) != NULL) {
        xup_kernel(h->K, rows, q, work);
        crba_kernel(h->K, rows, work, H);
    }
    scratch_free(buf, stack);
    return out;
}

PyDoc_STRVAR(generalized_momentum_doc,
"generalized_momentum(kernels, q, qd) -> (M(q) qd, C(q, qd)^T qd), each (n,), or None.");

static PyObject *
c_generalized_momentum(PyObject *module, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 3) {
        PyErr_SetString(PyExc_TypeError, "generalized_momentum takes 3 arguments");
        return NULL;
    }
    KernelsObject *h = kernels_arg(args[0]);
    if (h == NULL)
        return NULL;
    const Py_ssize_t n = h->n, rows = h->rows;
    double stack[STACK_DOUBLES];
    double *buf = scratch(stack, 2 * n + rows * WORK);
    if (buf == NULL)
        return NULL;
    double *q = buf, *qd = q + n, *work = qd + n;
    PyObject *out = NULL, *mom = NULL, *ctq = NULL;
    double *vm, *vc;
    if (!(as_doubles(args[1], n, q) && as_doubles(args[2], n, qd))) {
        out = Py_None;
        Py_INCREF(out);
        goto done;
    }
    if ((mom = new_array(1, h->nn, &vm)) == NULL || (ctq = new_array(1, h->nn, &vc)) == NULL)
        goto done;
    xup_kernel(h->K, rows, q, work);
    momentum_kernel(h->K, rows, q, qd, vm, vc, work);
    out = PyTuple_Pack(2, mom, ctq);
done:
    Py_XDECREF(mom);
    Py_XDECREF(ctq);
    scratch_free(buf, stack);
    return out;
}

PyDoc_STRVAR(regressor_doc,
"regressor(kernels, q, qd, qdd, gravity) -> Y (n, 10 NB), or None\n\n"
"The joint-torque regressor of one state (tau = Y pi, pi the ten inertial parameters of\n"
"each body); arguments as for rnea, None when one is not such a state.");

static PyObject *
c_regressor(PyObject *module, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 5) {
        PyErr_SetString(PyExc_TypeError, "regressor takes 5 arguments");
        return NULL;
    }
    KernelsObject *h = kernels_arg(args[0]);
    if (h == NULL)
        return NULL;
    const Py_ssize_t n = h->n, rows = h->rows;
    double stack[STACK_DOUBLES];
    double *buf = scratch(stack, 3 * n + 3 + rows * WORK + 6 * rows * rows);
    if (buf == NULL)
        return NULL;
    double *q = buf, *qd = q + n, *qdd = qd + n, *g = qdd + n, *work = g + 3;
    double *axes = work + rows * WORK;
    PyObject *out = NULL;
    double *Y;
    if (!(as_doubles(args[1], n, q) && as_doubles(args[2], n, qd)
          && as_doubles(args[3], n, qdd) && as_doubles(args[4], 3, g))) {
        out = Py_None;
        Py_INCREF(out);
    } else if ((out = new_array(2, h->ny, &Y)) != NULL) {
        xup_kernel(h->K, rows, q, work);
        regressor_kernel(h->K, rows, qd, qdd, g[0], g[1], g[2], Y, axes, work);
    }
    scratch_free(buf, stack);
    return out;
}

/* ------------------------------------------------------------------------------------------
 * Batches: contiguous slices of the states on threads, without the GIL */

enum { RNEA = 0, CRBA = 1, MOMENTUM = 2, REGRESSOR = 3 };

typedef struct {
    int kind;
    const double *K;
    long rows, n;
    const double *q, *qd, *qdd, *fext;  /* (N, n) each; fext (1 or N, rows, 6) or NULL */
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
    const long n = s->n, rows = s->rows;
    if (work == NULL)
        return -1;
#ifdef SD_LANES
    if (s->kind == RNEA) {
        /* several states at once (SIMD across states), the same bits as one by one */
        const double *f = s->fext ? s->fext + (s->fext_per_state ? lo : 0) * rows * 6 : NULL;
        long done = rnea_batch_lanes(s->K, rows, (long)(hi - lo), s->q + lo * n,
                                     s->qd + lo * n, s->qdd + lo * n, s->g[0], s->g[1],
                                     s->g[2], f, s->fext_per_state, s->out1 + lo * n);
        if (done < 0)
            return -1;
        lo += done;
    }
#endif
    for (Py_ssize_t k = lo; k < hi; k++) {
        const double *q = s->q + k * n;
        xup_kernel(s->K, rows, q, work);
        if (s->kind == RNEA) {
            const double *f = s->fext ? s->fext + (s->fext_per_state ? k : 0) * rows * 6 : NULL;
            rnea_kernel(s->K, rows, q, s->qd + k * n, s->qdd + k * n, s->g[0], s->g[1],
                        s->g[2], f, f != NULL, s->out1 + k * n, work);
        } else if (s->kind == CRBA) {
            crba_kernel(s->K, rows, work, s->out1 + k * n * n);
        } else if (s->kind == REGRESSOR) {
            regressor_kernel(s->K, rows, s->qd + k * n, s->qdd + k * n, s->g[0], s->g[1],
                             s->g[2], s->out1 + k * n * 10 * (rows - 1), work + rows * WORK,
                             work);
        } else {
            momentum_kernel(s->K, rows, q, s->qd + k * n, s->out1 + k * n, s->out2 + k * n,
                            work);
        }
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
    /* the regressor's carried axes after the per-body scratch */
    double *work = malloc(sizeof(double) * (rows * WORK
                                            + (s->kind == REGRESSOR ? 6 * rows * rows : 0)));
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

/* Buffers of a batch call: inputs read-only, outputs writable; each C-contiguous float64
 * holding sizes[i] doubles. On an error none is held. */
static int
batch_buffers(PyObject *const *objs, Py_buffer *views, int count, const int *writable,
              const Py_ssize_t *sizes, const char *const *names)
{
    for (int i = 0; i < count; i++) {
        int ok = get_table(objs[i], &views[i], writable[i], names[i]) == 0;
        if (ok && views[i].len != (Py_ssize_t)sizeof(double) * sizes[i]) {
            PyBuffer_Release(&views[i]);
            PyErr_Format(PyExc_ValueError, "%s must hold %zd numbers", names[i], sizes[i]);
            ok = 0;
        }
        if (!ok) {
            for (int j = 0; j < i; j++)
                PyBuffer_Release(&views[j]);
            return -1;
        }
    }
    return 0;
}

static void
release_all(Py_buffer *views, int count)
{
    for (int i = 0; i < count; i++)
        PyBuffer_Release(&views[i]);
}

PyDoc_STRVAR(rnea_batch_doc,
"rnea_batch(kernels, N, q, qd, qdd, gravity, fext, tau, threads) -> None\n\n"
"N states: q, qd, qdd C-contiguous float64 of N x n numbers, gravity 3 numbers, fext None\n"
"or C-contiguous float64 of rows x 6 (shared) or N x rows x 6 numbers; writes tau (N x n).\n"
"Releases the GIL; up to `threads` threads.");

static PyObject *
c_rnea_batch(PyObject *module, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 9) {
        PyErr_SetString(PyExc_TypeError, "rnea_batch takes 9 arguments");
        return NULL;
    }
    KernelsObject *h = kernels_arg(args[0]);
    Py_ssize_t N = PyLong_AsSsize_t(args[1]);
    long threads = PyLong_AsLong(args[8]);
    if (h == NULL || PyErr_Occurred())
        return NULL;
    Slice job = {.kind = RNEA, .K = h->K, .rows = h->rows, .n = h->n};
    if (!as_doubles(args[5], 3, job.g)) {
        PyErr_SetString(PyExc_TypeError, "gravity must be 3 numbers");
        return NULL;
    }
    PyObject *objs[4] = {args[2], args[3], args[4], args[7]};
    const int writable[4] = {0, 0, 0, 1};
    const Py_ssize_t sizes[4] = {N * h->n, N * h->n, N * h->n, N * h->n};
    const char *const names[4] = {"q", "qd", "qdd", "tau"};
    Py_buffer v[5];
    if (batch_buffers(objs, v, 4, writable, sizes, names) < 0)
        return NULL;
    int nviews = 4;
    if (args[6] != Py_None) {
        if (get_table(args[6], &v[4], 0, "fext") < 0) {
            release_all(v, 4);
            return NULL;
        }
        nviews = 5;
        Py_ssize_t m = v[4].len / (Py_ssize_t)sizeof(double);
        if (m != h->rows * 6 && m != N * h->rows * 6) {
            release_all(v, 5);
            PyErr_SetString(PyExc_ValueError, "fext must hold rows x 6 or N x rows x 6 numbers");
            return NULL;
        }
        job.fext = v[4].buf;
        job.fext_per_state = m != h->rows * 6;
    }
    job.q = v[0].buf;
    job.qd = v[1].buf;
    job.qdd = v[2].buf;
    job.out1 = v[3].buf;
    int rc = run_batch(&job, N, threads);
    release_all(v, nviews);
    if (rc < 0)
        return NULL;
    Py_RETURN_NONE;
}

PyDoc_STRVAR(mass_matrix_batch_doc,
"mass_matrix_batch(kernels, N, q, H, threads) -> None: M(q) of N states into H (N x n x n).");

static PyObject *
c_mass_matrix_batch(PyObject *module, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 5) {
        PyErr_SetString(PyExc_TypeError, "mass_matrix_batch takes 5 arguments");
        return NULL;
    }
    KernelsObject *h = kernels_arg(args[0]);
    Py_ssize_t N = PyLong_AsSsize_t(args[1]);
    long threads = PyLong_AsLong(args[4]);
    if (h == NULL || PyErr_Occurred())
        return NULL;
    Slice job = {.kind = CRBA, .K = h->K, .rows = h->rows, .n = h->n};
    PyObject *objs[2] = {args[2], args[3]};
    const int writable[2] = {0, 1};
    const Py_ssize_t sizes[2] = {N * h->n, N * h->n * h->n};
    const char *const names[2] = {"q", "H"};
    Py_buffer v[2];
    if (batch_buffers(objs, v, 2, writable, sizes, names) < 0)
        return NULL;
    job.q = v[0].buf;
    job.out1 = v[1].buf;
    int rc = run_batch(&job, N, threads);
    release_all(v, 2);
    if (rc < 0)
        return NULL;
    Py_RETURN_NONE;
}

PyDoc_STRVAR(momentum_batch_doc,
"momentum_batch(kernels, N, q, qd, mom, ctq, threads) -> None: M(q) qd and C^T qd of N\n"
"states into mom and ctq (N x n each).");

static PyObject *
c_momentum_batch(PyObject *module, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 7) {
        PyErr_SetString(PyExc_TypeError, "momentum_batch takes 7 arguments");
        return NULL;
    }
    KernelsObject *h = kernels_arg(args[0]);
    Py_ssize_t N = PyLong_AsSsize_t(args[1]);
    long threads = PyLong_AsLong(args[6]);
    if (h == NULL || PyErr_Occurred())
        return NULL;
    Slice job = {.kind = MOMENTUM, .K = h->K, .rows = h->rows, .n = h->n};
    PyObject *objs[4] = {args[2], args[3], args[4], args[5]};
    const int writable[4] = {0, 0, 1, 1};
    const Py_ssize_t sizes[4] = {N * h->n, N * h->n, N * h->n, N * h->n};
    const char *const names[4] = {"q", "qd", "mom", "ctq"};
    Py_buffer v[4];
    if (batch_buffers(objs, v, 4, writable, sizes, names) < 0)
        return NULL;
    job.q = v[0].buf;
    job.qd = v[1].buf;
    job.out1 = v[2].buf;
    job.out2 = v[3].buf;
    int rc = run_batch(&job, N, threads);
    release_all(v, 4);
    if (rc < 0)
        return NULL;
    Py_RETURN_NONE;
}

PyDoc_STRVAR(regressor_batch_doc,
"regressor_batch(kernels, N, q, qd, qdd, gravity, Y, threads) -> None: the regressors of N\n"
"states (q, qd, qdd N x n each, gravity 3 numbers) into Y (N x n x 10 NB).");

static PyObject *
c_regressor_batch(PyObject *module, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 8) {
        PyErr_SetString(PyExc_TypeError, "regressor_batch takes 8 arguments");
        return NULL;
    }
    KernelsObject *h = kernels_arg(args[0]);
    Py_ssize_t N = PyLong_AsSsize_t(args[1]);
    long threads = PyLong_AsLong(args[7]);
    if (h == NULL || PyErr_Occurred())
        return NULL;
    Slice job = {.kind = REGRESSOR, .K = h->K, .rows = h->rows, .n = h->n};
    if (!as_doubles(args[5], 3, job.g)) {
        PyErr_SetString(PyExc_TypeError, "gravity must be 3 numbers");
        return NULL;
    }
    PyObject *objs[4] = {args[2], args[3], args[4], args[6]};
    const int writable[4] = {0, 0, 0, 1};
    const Py_ssize_t sizes[4] = {N * h->n, N * h->n, N * h->n, N * h->n * 10 * (h->rows - 1)};
    const char *const names[4] = {"q", "qd", "qdd", "Y"};
    Py_buffer v[4];
    if (batch_buffers(objs, v, 4, writable, sizes, names) < 0)
        return NULL;
    job.q = v[0].buf;
    job.qd = v[1].buf;
    job.qdd = v[2].buf;
    job.out1 = v[3].buf;
    int rc = run_batch(&job, N, threads);
    release_all(v, 4);
    if (rc < 0)
        return NULL;
    Py_RETURN_NONE;
}

/* ------------------------------------------------------------------------------------------
 * Door: a public function of spatial_dynamics entered in C
 *
 * Door(function, kind, kernels, gravity) is called as `function` is (same arguments, and it carries
 * its __doc__, __name__ and __wrapped__). One state with gravity given or default, no f_ext
 * (`gravity` when not given) and backend 'auto' or 'compiled', of a model whose Kernels are
 * in the dict `kernels`
 * (id(model) -> Kernels), runs here; every other call, or one whose arguments the entry
 * declines, is passed on to `function` unchanged (it validates, derives the table, runs
 * batches and the other backends). This saves the Python frame of `function` (~0.2 µs, a
 * fifth of a call) on the path users take most. The door keeps the last model it answered
 * (a weak reference) and its Kernels, so that a run of calls on one model skips the dict. */

enum { D_RNEA = 0, D_GRAVITY = 1, D_BIAS = 2, D_MASS = 3, D_MOMENTUM = 4 };
/* joint-vector arguments after the model, and whether gravity and f_ext come next */
static const int door_vectors[] = {3, 1, 2, 1, 2};
static const int door_gravity[] = {1, 1, 1, 0, 0};
static const int door_fext[] = {1, 0, 0, 0, 0};

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
    PyObject *last_kern;  /* its Kernels */
} DoorObject;

/* Whether the model of the last call is `model` (alive: its Kernels are still in the dict,
 * removed only when the model is collected). Saves the dict look-up (~40 ns) of each call
 * on one model. */
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
    return PyWeakref_GET_OBJECT(self->last_model) == model;
#endif
}

static int
is_name(PyObject *name, PyObject *interned)
{
    return name == interned || PyUnicode_Compare(name, interned) == 0;
}

static PyObject *
door_call(DoorObject *self, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    Py_ssize_t nargs = PyVectorcall_NARGS(nargsf);
    const int kind = self->kind, nv = door_vectors[kind];
    PyObject *gravity = self->gravity, *f_ext = NULL, *backend = NULL;
    Py_ssize_t nkw = kwnames ? PyTuple_GET_SIZE(kwnames) : 0;
    int ok = nargs >= 1 + nv;
    /* optional arguments by position: gravity, f_ext, backend (those the function has) */
    Py_ssize_t k = 1 + nv;
    if (ok && door_gravity[kind] && k < nargs)
        gravity = args[k++];
    if (ok && door_fext[kind] && k < nargs)
        f_ext = args[k++];
    if (ok && k < nargs)
        backend = args[k++];
    ok = ok && k == nargs;
    for (Py_ssize_t i = 0; ok && i < nkw; i++) {
        PyObject *name = PyTuple_GET_ITEM(kwnames, i), *value = args[nargs + i];
        if (door_gravity[kind] && is_name(name, str_gravity))
            gravity = value;
        else if (door_fext[kind] && is_name(name, str_f_ext))
            f_ext = value;
        else if (is_name(name, str_backend))
            backend = value;
        else
            ok = 0;
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
            PyObject *ref = PyWeakref_NewRef(args[0], NULL);
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
        PyObject *call[5] = {kern, args[1], NULL, NULL, NULL};
        PyObject *out;
        switch (kind) {
        case D_RNEA:
            call[2] = args[2], call[3] = args[3], call[4] = gravity;
            out = c_rnea(NULL, call, 5);
            break;
        case D_GRAVITY:
            call[2] = gravity;
            out = c_gravity_torque(NULL, call, 3);
            break;
        case D_BIAS:
            call[2] = args[2], call[3] = gravity;
            out = c_bias_torque(NULL, call, 4);
            break;
        case D_MASS:
            out = c_mass_matrix(NULL, call, 2);
            break;
        default:
            call[2] = args[2];
            out = c_generalized_momentum(NULL, call, 3);
        }
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
    if (kind < D_RNEA || kind > D_MOMENTUM || !PyCallable_Check(function)) {
        PyErr_SetString(PyExc_ValueError, "Door: a callable and a kind in 0..4");
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

static int
door_traverse(DoorObject *self, visitproc visit, void *arg)
{
    Py_VISIT(self->function);
    Py_VISIT(self->kernels);
    Py_VISIT(self->gravity);
    Py_VISIT(self->dict);
    Py_VISIT(self->last_model);
    Py_VISIT(self->last_kern);
    return 0;
}

static int
door_clear(DoorObject *self)
{
    Py_CLEAR(self->function);
    Py_CLEAR(self->kernels);
    Py_CLEAR(self->gravity);
    Py_CLEAR(self->dict);
    Py_CLEAR(self->last_model);
    Py_CLEAR(self->last_kern);
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
};

/* ------------------------------------------------------------------------------------------
 * The module */

static PyMethodDef methods[] = {
    {"rnea", (PyCFunction)(void (*)(void))c_rnea, METH_FASTCALL, rnea_doc},
    {"gravity_torque", (PyCFunction)(void (*)(void))c_gravity_torque, METH_FASTCALL,
     gravity_torque_doc},
    {"bias_torque", (PyCFunction)(void (*)(void))c_bias_torque, METH_FASTCALL, bias_torque_doc},
    {"mass_matrix", (PyCFunction)(void (*)(void))c_mass_matrix, METH_FASTCALL,
     mass_matrix_doc},
    {"generalized_momentum", (PyCFunction)(void (*)(void))c_generalized_momentum,
     METH_FASTCALL, generalized_momentum_doc},
    {"regressor", (PyCFunction)(void (*)(void))c_regressor, METH_FASTCALL, regressor_doc},
    {"rnea_batch", (PyCFunction)(void (*)(void))c_rnea_batch, METH_FASTCALL, rnea_batch_doc},
    {"mass_matrix_batch", (PyCFunction)(void (*)(void))c_mass_matrix_batch, METH_FASTCALL,
     mass_matrix_batch_doc},
    {"momentum_batch", (PyCFunction)(void (*)(void))c_momentum_batch, METH_FASTCALL,
     momentum_batch_doc},
    {"regressor_batch", (PyCFunction)(void (*)(void))c_regressor_batch, METH_FASTCALL,
     regressor_batch_doc},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT,
    .m_name = "spatial_dynamics.backends._compiled",
    .m_doc = PyDoc_STR("The generated kernels, compiled when the package is built."),
    .m_size = -1,
    .m_methods = methods,
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

/* Copyright 2026 spatial_dynamics contributors
 * SPDX-License-Identifier: Apache-2.0
 *
 * The algorithms and their entries. Each algorithm is one row of ALGORITHMS (which joint
 * vectors it reads, whether gravity and external forces, which generated kernel it runs);
 * one generic single-state entry (single) and one generic batch entry (batch) serve them
 * all, as the module's functions rnea, mass_matrix, rnea_batch, ...
 *
 * A single-state entry (METH_FASTCALL) reads its arguments with as_doubles (arguments.c),
 * or returns None when one is not such a state. Results are new numpy arrays, float32 when
 * every joint vector is float32 (the dtype numpy's promotion gives; computed in float64 and
 * rounded once), else float64. A batch entry takes C-contiguous float64 arrays prepared by
 * the caller and hands the states to run_batch (threads.c).
 */
#include "_compiled.h"

/* Scratch of a single call on the C stack up to this many doubles (32 KiB), else the heap. */
#define STACK_DOUBLES 4096

/* ------------------------------------------------------------------------------------------
 * The algorithms: one row each, read by the generic entries below */

const Algorithm ALGORITHMS[] = {
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
    {"bodies", "bodies_batch", 1, 0, 0, BODIES, {"J"},
     "bodies(kernels, q) -> (NB + 1, 16 + 6 n), or None\n\n"
     "Each body's row: its placement [R p; 0 0 0 1] (4 x 4 row-major: orientation world <- body,\n"
     "origin), then its Jacobian (6 x n row-major, angular rows first) at its origin in world\n"
     "axes.",
     "bodies_batch(kernels, N, q, J, threads) -> None: the rows of bodies() of N states into\n"
     "J (N x (NB + 1) x (16 + 6 n))."},
    {"rnea_derivatives", "derivatives_batch", 3, 1, 1, DERIVATIVES, {"dq", "dqd", "M"},
     "rnea_derivatives(kernels, q, qd, qdd, gravity, f_body=None, out=None) -> (dq, dqd, M),\n"
     "or None\n\n"
     "The analytical derivatives of rnea (algorithms/derivatives.py) of one state: dtau/dq\n"
     "(tangent space), dtau/dqd and M = dtau/dqdd, each a new (n, n) array, or written into\n"
     "out: a tuple of three numpy arrays (exactly ndarray), float64, C-contiguous, writeable,\n"
     "(n, n) each (None when they are not, or the result would be float32); arguments as\n"
     "for rnea.",
     "derivatives_batch(kernels, N, q, qd, qdd, gravity, fext, dq, dqd, M, threads) -> None:\n"
     "the derivatives of N states into dq, dqd and M (N x n x n each); fext as for\n"
     "rnea_batch."},
    {"forward_dynamics", "forward_dynamics_batch", 3, 1, 1, FORWARD, {"qdd"},
     "forward_dynamics(kernels, q, qd, tau, gravity, f_body=None, armature=None) -> qdd (n,),\n"
     "or None\n\n"
     "One state: qdd = (M(q) + diag(armature))^-1 (tau - h(q, qd)), h the rnea at qdd = 0, by\n"
     "the articulated-body algorithm (algorithms/aba.py; M's factorization where two bodies\n"
     "share a coordinate); arguments as for rnea, tau in place of qdd, armature n numbers or\n"
     "None. None when an argument is not such a state, or a pivot d_k is at most\n"
     "PIVOT_TOL M_kk (the caller's general path names the joint), or a model with armature\n"
     "has no ABA.",
     "forward_dynamics_batch(kernels, N, q, qd, tau, gravity, fext, qdd, threads) -> None\n\n"
     "N states as rnea_batch, tau in place of qdd; writes qdd (N x n), NaN in a state whose M\n"
     "has a pivot d_k at most PIVOT_TOL M_kk."},
};
#define ROWS (sizeof ALGORITHMS / sizeof ALGORITHMS[0])
const int ALGORITHM_COUNT = (int)ROWS;

static const char *const VECTOR_NAMES[3] = {"q", "qd", "qdd"};

/* The first argument of every entry, a Kernels; NULL with a TypeError if not. */
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

/* ------------------------------------------------------------------------------------------
 * One state: the entry of every algorithm */

/* The bytes [*lo, *hi) that the elements of `arr` lie in (any strides; empty: lo == hi). */
static void
extent(PyArrayObject *arr, const char **lo, const char **hi)
{
    const char *p = PyArray_BYTES(arr);
    npy_intp low = 0, high = PyArray_ITEMSIZE(arr);
    for (int d = 0; d < PyArray_NDIM(arr); d++) {
        const npy_intp dim = PyArray_DIM(arr, d), stride = PyArray_STRIDE(arr, d);
        if (dim == 0) {
            *lo = *hi = p;
            return;
        }
        if (stride < 0)
            low += stride * (dim - 1);
        else
            high += stride * (dim - 1);
    }
    *lo = p + low;
    *hi = p + high;
}

/* Whether the `count` arrays of the tuple `out` certainly share no memory with each other
 * or with the arguments args[1..nargs): bounds that do not meet. An argument that is an
 * exact ndarray is bounded; a list, tuple, number or None holds no array memory; anything
 * else (another buffer) may share: 0, and the caller's exact check decides. */
static int
apart(PyObject *out, int count, PyObject *const *args, Py_ssize_t nargs)
{
    const char *lo[3], *hi[3];
    for (int k = 0; k < count; k++) {
        extent((PyArrayObject *)PyTuple_GET_ITEM(out, k), &lo[k], &hi[k]);
        for (int j = 0; j < k; j++)
            if (lo[k] < hi[j] && lo[j] < hi[k])
                return 0;
    }
    for (Py_ssize_t i = 1; i < nargs; i++) {
        PyObject *x = args[i];
        if (PyList_CheckExact(x) || PyTuple_CheckExact(x) || PyFloat_CheckExact(x)
                || PyLong_CheckExact(x) || x == Py_None)
            continue;
        if (!PyArray_CheckExact(x))
            return 0;
        const char *xlo, *xhi;
        extent((PyArrayObject *)x, &xlo, &xhi);
        for (int k = 0; k < count; k++)
            if (xlo < hi[k] && lo[k] < xhi)
                return 0;
    }
    return 1;
}

/* args: kernels, the joint vectors, gravity (if the algorithm reads it), f_body (optional,
 * if it takes one), then FORWARD's armature or DERIVATIVES' out (optional). None when a
 * vector or gravity is not one state that as_doubles reads. The results are float32 when
 * every joint vector is float32 (what numpy's promotion of them gives), computed in float64
 * and rounded once; else float64. out (None, or a tuple of as many arrays as results): the
 * results are written into them when each is an exact ndarray, float64, C-contiguous,
 * aligned, writeable and of the result's shape, their bounds meet neither each other's nor
 * an argument's (apart), and the results are float64; else None (the caller checks exactly,
 * refuses or copies). */
PyObject *
single(const Algorithm *a, PyObject *const *args, Py_ssize_t nargs)
{
    const Py_ssize_t fixed = 1 + a->vectors + a->gravity;
    /* + FORWARD's armature, DERIVATIVES' out */
    const Py_ssize_t most = fixed + a->fext + (a->kernel == FORWARD || a->kernel == DERIVATIVES);
    if (nargs < fixed || nargs > most) {
        PyErr_Format(PyExc_TypeError,
                     most > fixed ? "%s takes %zd to %zd arguments" : "%s takes %zd arguments",
                     a->name, fixed, most);
        return NULL;
    }
    KernelsObject *h = kernels_arg(args[0]);
    if (h == NULL)
        return NULL;
    const Py_ssize_t n = h->n, rows = h->rows;
    npy_intp dims[2];
    int count;
    const int ndim = result_shape(h, a->kernel, dims, &count);
    PyObject *given = nargs > fixed + 1 && a->kernel == DERIVATIVES ? args[fixed + 1] : Py_None;
    if (given != Py_None) {
        if (!PyTuple_CheckExact(given) || PyTuple_GET_SIZE(given) != count)
            Py_RETURN_NONE;
        for (int k = 0; k < count; k++) {
            PyObject *o = PyTuple_GET_ITEM(given, k);
            PyArrayObject *arr = (PyArrayObject *)o;
            if (!PyArray_CheckExact(o) || PyArray_TYPE(arr) != NPY_DOUBLE
                    || !PyArray_ISCARRAY(arr) || PyArray_NDIM(arr) != ndim)
                Py_RETURN_NONE;
            for (int d = 0; d < ndim; d++)
                if (PyArray_DIM(arr, d) != dims[d])
                    Py_RETURN_NONE;
        }
        if (!apart(given, count, args, fixed + 1))     /* the vectors, gravity, f_body */
            Py_RETURN_NONE;
    }
    const Py_ssize_t size = dims[0] * dims[1];
    /* Room for float32 results, computed in doubles first, only when q may be float32. */
    PyObject *q_arg = args[1];
    const int may_float = PyArray_Check(q_arg)
        ? PyArray_TYPE((PyArrayObject *)q_arg) == NPY_FLOAT
        : !(PyList_CheckExact(q_arg) || PyTuple_CheckExact(q_arg));
    double stack[STACK_DOUBLES];
    const Py_ssize_t nv = h->nv;
    double *buf = scratch(stack, n + 3 * nv + 3 + (may_float ? count * size : 0)
                                 + work_size(a->kernel, rows, h->nv));
    if (buf == NULL)
        return NULL;
    double *x[3] = {buf, buf + n, buf + n + nv}, *g = buf + n + 2 * nv, *res = g + 3;
    double *arm = res + (may_float ? count * size : 0), *work = arm + nv;
    const double *armature = NULL;
    PyObject *results[3] = {NULL, NULL, NULL}, *out = NULL;
    Py_buffer fb = {0};
    const double *f = NULL;
    int floats = 0;         /* joint vectors read from float32 */
    for (int i = 0; i < a->vectors; i++) {
        const int read = as_doubles(args[1 + i], i == 0 ? n : nv, x[i]);
        if (read == DECLINED)
            goto declined;
        floats += read == AS_FLOAT;
    }
    if (h->quaternion >= 0) {
        /* a quaternion off unit (or not finite) is the general path's named ValueError */
        const double *u = x[0] + h->quaternion;
        const double n2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2] + u[3] * u[3];
        if (!(n2 >= UNIT_SQUARED_LOW && n2 <= UNIT_SQUARED_HIGH))
            goto declined;
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
    if (a->kernel == FORWARD && nargs > fixed + 1 && args[fixed + 1] != Py_None) {
        if (!as_doubles(args[fixed + 1], nv, arm))
            goto declined;
        armature = arm;
    }
    const int single_precision = may_float && floats == a->vectors;   /* res has room */
    double *data[3] = {NULL, NULL, NULL};
    if (given != Py_None) {
        if (single_precision)
            goto declined;      /* float32 results: the caller's */
        for (int k = 0; k < count; k++)
            data[k] = (double *)PyArray_DATA((PyArrayObject *)PyTuple_GET_ITEM(given, k));
        if (run_state(a->kernel, h->K, rows, x[0], x[1], x[2], g, f, armature, data[0],
                      data[1], data[2], work) < 0)
            goto declined;
        out = given;
        Py_INCREF(out);
        goto done;
    }
    for (int k = 0; k < count; k++) {
        results[k] = PyArray_SimpleNew(ndim, dims, single_precision ? NPY_FLOAT : NPY_DOUBLE);
        if (results[k] == NULL)
            goto done;
        data[k] = single_precision ? res + k * size
                                   : (double *)PyArray_DATA((PyArrayObject *)results[k]);
    }
    if (run_state(a->kernel, h->K, rows, x[0], x[1], x[2], g, f, armature, data[0], data[1],
                  data[2], work) < 0)
        goto declined;      /* M not positive definite: the general path names the joint */
    for (int k = 0; single_precision && k < count; k++) {
        float *out32 = (float *)PyArray_DATA((PyArrayObject *)results[k]);
        for (Py_ssize_t i = 0; i < size; i++)
            out32[i] = (float)data[k][i];
    }
    if (count == 1) {
        out = results[0];       /* its reference */
        results[0] = NULL;
    } else {
        out = count == 2 ? PyTuple_Pack(2, results[0], results[1])
                         : PyTuple_Pack(3, results[0], results[1], results[2]);
    }
    goto done;
declined:
    out = Py_None;
    Py_INCREF(out);
done:
    Py_XDECREF(results[0]);
    Py_XDECREF(results[1]);
    Py_XDECREF(results[2]);
    if (fb.obj != NULL)
        PyBuffer_Release(&fb);
    scratch_free(buf, stack);
    return out;
}

/* ------------------------------------------------------------------------------------------
 * Batches: the entry of every algorithm that has one */

/* args: kernels, N, the joint vectors (C-contiguous float64, N x n each), gravity (if the
 * algorithm reads it), fext (if it takes one: None, or C-contiguous float64 of rows x 6 or
 * N x rows x 6), the results (C-contiguous float64, writable), threads. */
static PyObject *
batch(const Algorithm *a, PyObject *const *args, Py_ssize_t nargs)
{
    npy_intp dims[2];
    int count;
    const int results = a->kernel == MOMENTUM ? 2 : (a->kernel == DERIVATIVES ? 3 : 1);
    const Py_ssize_t want = 2 + a->vectors + a->gravity + a->fext + results;
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
    Py_buffer v[7];     /* three joint vectors, three results, the external forces */
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
    job.out2 = count >= 2 ? v[a->vectors + 1].buf : NULL;
    job.out3 = count == 3 ? v[a->vectors + 2].buf : NULL;
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

/* ------------------------------------------------------------------------------------------
 * The module's functions: `self` is the index of their row in ALGORITHMS (entries_add) */

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

/* The functions' definitions, two a row of ALGORITHMS (single state, batch), filled in by
 * entries_add; each function's `self` is its row's index, which c_single and c_batch read. */
static PyMethodDef entries[2 * ROWS];

/* Add the entries of ALGORITHMS to m, and ALGORITHMS: their names in order (the doors'
 * kinds). */
int
entries_add(PyObject *m)
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

/* Copyright 2026 spatial_dynamics contributors
 * SPDX-License-Identifier: Apache-2.0
 *
 * Kernels: a model's table, and the generated kernels run on it. A Kernels object holds a
 * copy of a model's table (the rows of backends/layout.py, prepared once in Python), checked
 * once so that no table makes the kernels read or write out of bounds. run_state runs one
 * state through the kernels of _kernels_generated.h, run_states a slice of a batch (the RNEA
 * and its derivatives several states at once in SIMD lanes). The only file of the extension
 * that includes the generated header: the others know its kernels by RNEA, CRBA, MOMENTUM,
 * REGRESSOR. Its two entries of their own: split (split_kernel on arrays the caller
 * prepares) and contact (one state's contact inverse dynamics, M q̈ + h to the base
 * residual, in one call).
 */
#include "_compiled.h"
#include <structmember.h>

#include <math.h>
#include <stddef.h>
#include <string.h>

/* Generated from spatial_dynamics/algorithms into the build directory by setup.py (on the
 * include path), never a file of the sources. */
#include <_kernels_generated.h>
#ifndef KERNELS_SHA256
#define KERNELS_SHA256 ""   /* setup.py defines the SHA-256 of the header it generated */
#endif

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
    if (checked_mul(rows, 6 * (Py_ssize_t)rows + WORK + DWORK + 6 * CWORK, MAX_DOUBLES,
                    &size) < 0
            || checked_mul(3 * (Py_ssize_t)n, (Py_ssize_t)n, MAX_DOUBLES, &size) < 0
            || checked_mul((Py_ssize_t)n, 10 * (Py_ssize_t)rows, MAX_DOUBLES, &size) < 0
            || checked_mul((Py_ssize_t)K[VIDX] + 2, (Py_ssize_t)K[VIDX] + 2, MAX_DOUBLES,
                           &size) < 0) {
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
    /* a free-flyer is the root link's joint only (layout.py), body 1 */
    self->quaternion = rows > 1 && K[WIDTH + 1] == FF ? (long)K[WIDTH + QIDX] + 3 : -1;
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

PyTypeObject KernelsType = {
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
 * The generated kernels on one state, or on a slice of a batch */

/* The results of `kernel` for one state: how many (momentum's two, the derivatives' three,
 * else one), their shape dims[:ndim] (returned), and dims[0] x dims[1] doubles each. */
int
result_shape(const KernelsObject *h, int kernel, npy_intp *dims, int *count)
{
    *count = kernel == MOMENTUM ? 2 : (kernel == DERIVATIVES ? 3 : 1);
    if (kernel == BODIES) {     /* a row per body: [R p; 0 1], then J (6 x nv) */
        dims[0] = h->rows;
        dims[1] = 16 + 6 * (npy_intp)h->nv;
        return 2;
    }
    dims[0] = h->nv;
    dims[1] = kernel == CRBA || kernel == DERIVATIVES
        ? h->nv : (kernel == REGRESSOR ? 10 * (npy_intp)(h->rows - 1) : 1);
    return kernel == CRBA || kernel == REGRESSOR || kernel == DERIVATIVES ? 2 : 1;
}

/* Scratch doubles of one state: the per-body rows, the regressor's carried axes, the
 * derivatives' per-body rows and columns (codegen.MORE_STORES); for forward dynamics the
 * larger of the articulated-body algorithm's per-body rows (AWORK), a free-flyer's 6 x 6
 * factor and its composite inertia's diagonal (42) and its status (1), and the
 * composite-rigid-body path's M (nv x nv), the coordinates' parents and chains (nv each), the
 * chains of one coordinate's ancestors (2 nv), M's diagonal (nv) and its status (1). */
Py_ssize_t
work_size(int kernel, long rows, long nv)
{
    const Py_ssize_t aba = (Py_ssize_t)rows * AWORK + 43;
    const Py_ssize_t crba = (Py_ssize_t)nv * ((Py_ssize_t)nv + 5) + 1;
    return (Py_ssize_t)rows * WORK
        + (kernel == REGRESSOR ? 6 * (Py_ssize_t)rows * ((Py_ssize_t)rows + 5) : 0)
        + (kernel == DERIVATIVES ? (Py_ssize_t)rows * (DWORK + 6 * CWORK) : 0)
        + (kernel == FORWARD ? (aba > crba ? aba : crba) : 0);
}

/* One state through the generated kernels: the body transforms, then `kernel`'s passes.
 * g: 3 numbers; f: rows x 6 external forces or NULL; out2: momentum's second result, out2
 * and out3 the derivatives' second and third (dtau/dqd, M). FORWARD reads tau in place of
 * qdd and arm (nv armatures, or NULL): q̈ by the articulated-body algorithm
 * (algorithms/aba.py); on a model where two
 * bodies share a coordinate (a mimic joint), or a pivot D_i <= PIVOT_TOL M_kk, by
 * q̈ = M⁻¹ (τ - h) (algorithms/forward.py) with h the RNEA at q̈ = 0; 0, or -1 (q̈ all
 * NaN) when M has a pivot d_k <= PIVOT_TOL M_kk (with armature: -1 at ABA's refusal). */
int
run_state(int kernel, const double *K, long rows, const double *q, const double *qd,
          const double *qdd, const double *g, const double *f, const double *arm,
          double *out1, double *out2, double *out3, double *work)
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
    case BODIES:
        bodies_kernel(K, rows, work, out1);
        break;
    case DERIVATIVES:
#ifdef SD_VEX
        if (__builtin_cpu_supports("avx")) {   /* the same operations, VEX encoded */
            derivatives_kernel_avx(K, rows, qd, qdd, g[0], g[1], g[2], f, f != NULL, out1,
                                   out2, out3, work);
            break;
        }
#endif
        derivatives_kernel(K, rows, qd, qdd, g[0], g[1], g[2], f, f != NULL, out1, out2, out3,
                           work);
        break;
    case FORWARD: {
        const long nv = (long)K[VIDX];
        double *H = work + (Py_ssize_t)rows * WORK, *lam = H + (Py_ssize_t)nv * nv;
        double *run = lam + nv, *seg = run + nv, *Hkk = seg + 2 * nv, *info = Hkk + nv;
        double *T = H + (Py_ssize_t)rows * AWORK;
        aba_kernel(K, rows, qd, qdd, g[0], g[1], g[2], f, f != NULL, arm ? arm : qdd,
                   arm != NULL, out1, T, T + 42, work);
        if (T[42] == -1.0)
            break;
        if (arm != NULL)
            return -1;      /* the general path adds the armature to M and names the joint */
        for (long k = 0; k < nv; k++)
            lam[k] = 0.0;       /* q̈ = 0: the bias h into out1 */
        rnea_kernel(K, rows, q, qd, lam, g[0], g[1], g[2], f, f != NULL, out1, work);
        for (long k = 0; k < nv; k++)
            out1[k] = qdd[k] - out1[k];
        crba_kernel(K, rows, work, H);
        forward_kernel(K, rows, H, out1, lam, run, seg, Hkk, info);
        if (info[0] >= 0.0) {
            for (long k = 0; k < nv; k++)
                out1[k] = NAN;
            return -1;
        }
        break;
    }
    default:
        regressor_kernel(K, rows, qd, qdd, g[0], g[1], g[2], out1,
                         work + (Py_ssize_t)rows * WORK, work);
    }
    return 0;
}

/* The states [lo, hi) of job s with the scratch `work`: 0, or -1 without memory. */
int
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
    if (s->kernel == DERIVATIVES && s->qd != NULL && s->qdd != NULL) {
        /* the same for the derivatives: several states at once, each one's bits */
        const double *f = s->fext ? s->fext + (s->fext_per_state ? lo : 0) * rows * 6 : NULL;
        long done = derivatives_batch_lanes(s->K, rows, (long)(hi - lo), s->q + lo * n,
                                            s->qd + lo * nv, s->qdd + lo * nv, s->g[0],
                                            s->g[1], s->g[2], f, s->fext_per_state,
                                            s->out1 + lo * s->size, s->out2 + lo * s->size,
                                            s->out3 + lo * s->size);
        if (done < 0)
            return -1;
        lo += done;
    }
#endif
    /* each state's results at k x size in each result (the derivatives' dtau/dq, dtau/dqd
     * and M in three) */
    for (Py_ssize_t k = lo; k < hi; k++) {
        const double *f = s->fext ? s->fext + (s->fext_per_state ? k : 0) * rows * 6 : NULL;
        run_state(s->kernel, s->K, rows, s->q + k * n, s->qd ? s->qd + k * nv : NULL,
                  s->qdd ? s->qdd + k * nv : NULL, s->g, f, NULL, s->out1 + k * s->size,
                  s->out2 ? s->out2 + k * s->size : NULL,
                  s->out3 ? s->out3 + k * s->size : NULL, work);
    }
    return 0;
}

/* ------------------------------------------------------------------------------------------
 * The contact-consistent split (algorithms/split.py), on arrays the caller prepares */

/* split(QR, k, wts, res, scr, tol) -> None; QR, res and scr C-contiguous float64, written. */
static PyObject *
c_split(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    if (nargs != 6) {
        PyErr_SetString(PyExc_TypeError, "split takes 6 arguments");
        return NULL;
    }
    const long k = PyLong_AsLong(args[1]);
    if (k == -1 && PyErr_Occurred())
        return NULL;
    const double tol = PyFloat_AsDouble(args[5]);
    if (tol == -1.0 && PyErr_Occurred())
        return NULL;
    PyObject *const objs[4] = {args[0], args[2], args[3], args[4]};
    static const char *const names[4] = {"QR", "wts", "res", "scr"};
    Py_buffer v[4];
    int held = 0;
    for (; held < 4; held++)
        if (get_table(objs[held], &v[held], held != 1, names[held]) < 0)
            goto fail;
    const Py_ssize_t d = (Py_ssize_t)sizeof(double), n = v[1].len / d, size = v[0].len / d;
    const Py_ssize_t cols = k + 1 + n, nv = k >= 0 ? size / cols : 0;
    if (k < 0 || n < 1 || nv * cols != size || nv < n || v[2].len / d < n + k + 2
            || v[3].len / d < k + (nv + k + 2) * nv || !(tol >= 0.0)) {
        PyErr_SetString(PyExc_ValueError, "split: QR must hold (k + 1 + n) x nv numbers "
                        "(n = len(wts)), res n + k + 2, scr k + (nv + k + 2) nv, tol >= 0");
        goto fail;
    }
    split_kernel(v[0].buf, k, (long)n, (long)(nv - n), v[1].buf, v[2].buf, v[3].buf, tol);
    for (int i = 0; i < held; i++)
        PyBuffer_Release(&v[i]);
    Py_RETURN_NONE;
fail:
    for (int i = 0; i < held; i++)
        PyBuffer_Release(&v[i]);
    return NULL;
}

/* ------------------------------------------------------------------------------------------
 * Contact inverse dynamics of one state, whole: M q̈ + h, J_c, the split, the base residual */

/* contact(kernels, q, qd, qdd, gravity, points, wts, tol, residual) -> (τ, λ, r), or None.
 *
 * points: C-contiguous float64, a row of five a contact: its body, its rows (3, a point's
 * force; 6, a surface's wrench) and r_c (3, the contact point in body coordinates). The
 * steps of contacts.py's general path on one float64 state: b = M q̈ + h (rnea_kernel);
 * every body's placement and Jacobian J_b (bodies_kernel); each contact's rows of J_c,
 * [1 0; -d× 1] J_b with d = R_b r_c (contact_jacobian's _contact_rows: ω, then v + ω × d,
 * a point keeps the v rows); the split of split_kernel on [J_cᵀ, b, Sᵀ]; the base rows'
 * residual b_base - J_c,baseᵀ λ, written into `residual` (6 float64). τ (n,) and λ (k,)
 * new arrays, r the rank found. None (the caller's general path then answers, or names what
 * is wrong) when q, qd, qdd or gravity is not one float64 state, when b or J_c is not finite
 * (or their squares overflow), for fewer than six contact rows, and for split_kernel's 1
 * (the numpy split's case). */
static PyObject *
c_contact(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    if (nargs != 9) {
        PyErr_SetString(PyExc_TypeError, "contact takes 9 arguments");
        return NULL;
    }
    if (!PyObject_TypeCheck(args[0], &KernelsType)) {
        PyErr_Format(PyExc_TypeError, "expected Kernels, got %.100s",
                     Py_TYPE(args[0])->tp_name);
        return NULL;
    }
    const KernelsObject *h = (const KernelsObject *)args[0];
    const double tol = PyFloat_AsDouble(args[7]);
    if (tol == -1.0 && PyErr_Occurred())
        return NULL;
    const long rows = h->rows, nq = h->n, nv = h->nv, n = nv - 6;
    Py_buffer pv, wv, rv;
    if (get_table(args[5], &pv, 0, "points") < 0)
        return NULL;
    if (get_table(args[6], &wv, 0, "wts") < 0) {
        PyBuffer_Release(&pv);
        return NULL;
    }
    if (get_table(args[8], &rv, 1, "residual") < 0) {
        PyBuffer_Release(&pv);
        PyBuffer_Release(&wv);
        return NULL;
    }
    const Py_ssize_t d = (Py_ssize_t)sizeof(double), nc = pv.len / d / 5;
    const double *P = pv.buf, *wts = wv.buf;
    long k = 0;
    int ok = h->quaternion >= 0 && n >= 1 && pv.len == nc * 5 * d && wv.len == n * d
             && rv.len == 6 * d && tol >= 0.0;
    for (Py_ssize_t c = 0; ok && c < nc; c++) {
        const double body = P[5 * c], m = P[5 * c + 1];
        ok = body >= 0.0 && body < (double)rows && body == (double)(long)body
             && (m == 3.0 || m == 6.0);
        k += (long)m;
    }
    PyObject *out = NULL;
    if (!ok) {
        PyErr_SetString(PyExc_ValueError, "contact: a floating-base model's kernels, points "
                        "of rows (body, 3 or 6, r_c), wts of nv - 6 numbers, tol >= 0, "
                        "residual of 6");
        goto release;
    }
    const long width = 16 + 6 * nv, cols = k + 1 + n;
    /* q, qd, qdd, gravity | work | the bodies' rows | b | QR | J_c,base | scr | res */
    const Py_ssize_t size = nq + 2 * nv + 3 + rows * WORK + rows * width + nv + cols * nv
                            + 6 * k + k + (nv + k + 2) * nv + n + k + 2;
    double *buf = PyMem_Malloc(sizeof(double) * size);
    if (buf == NULL) {
        PyErr_NoMemory();
        goto release;
    }
    double *x[3] = {buf, buf + nq, buf + nq + nv}, *g = buf + nq + 2 * nv, *work = g + 3;
    double *B = work + rows * WORK, *b = B + rows * width, *QR = b + nv, *base = QR + cols * nv;
    double *scr = base + 6 * k, *res = scr + k + (nv + k + 2) * nv;
    for (int i = 0; i < 3; i++)
        if (as_doubles(args[1 + i], i == 0 ? nq : nv, x[i]) != AS_DOUBLE)
            goto declined;
    {
        /* a quaternion off unit (or not finite) is the general path's named ValueError */
        const double *u = x[0] + h->quaternion;
        const double n2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2] + u[3] * u[3];
        if (!(n2 >= UNIT_SQUARED_LOW && n2 <= UNIT_SQUARED_HIGH))
            goto declined;
    }
    if (!as_doubles(args[4], 3, g) || k < 6)
        goto declined;
    xup_kernel(h->K, rows, x[0], work);
    bodies_kernel(h->K, rows, work, B);
    rnea_kernel(h->K, rows, x[0], x[1], x[2], g[0], g[1], g[2], NULL, 0, b, work);
    /* [J_cᵀ, b, Sᵀ] by columns: column r is row r of J_c */
    double squares = 0.0;
    long r = 0;
    for (Py_ssize_t c = 0; c < nc; c++) {
        const double *H = B + (long)P[5 * c] * width, *J = H + 16, *rc = P + 5 * c + 2;
        const double d0 = H[0] * rc[0] + H[1] * rc[1] + H[2] * rc[2];
        const double d1 = H[4] * rc[0] + H[5] * rc[1] + H[6] * rc[2];
        const double d2 = H[8] * rc[0] + H[9] * rc[1] + H[10] * rc[2];
        if (P[5 * c + 1] == 6.0)
            for (long a = 0; a < 3; a++, r++)
                for (long i = 0; i < nv; i++)
                    QR[r * nv + i] = J[a * nv + i];
        for (long i = 0; i < nv; i++) {
            const double w0 = J[i], w1 = J[nv + i], w2 = J[2 * nv + i];
            QR[r * nv + i] = J[3 * nv + i] + (d2 * w1 - d1 * w2);
            QR[(r + 1) * nv + i] = J[4 * nv + i] + (d0 * w2 - d2 * w0);
            QR[(r + 2) * nv + i] = J[5 * nv + i] + (d1 * w0 - d0 * w1);
        }
        r += 3;
    }
    for (long i = 0; i < k * nv; i++)
        squares += QR[i] * QR[i];
    for (long i = 0; i < nv; i++) {
        QR[k * nv + i] = b[i];
        squares += b[i] * b[i];
    }
    for (long i = 0; i < n * nv; i++)
        QR[(k + 1) * nv + i] = 0.0;
    for (long c = 0; c < n; c++)
        QR[(k + 1 + c) * nv + 6 + c] = 1.0;
    for (long r2 = 0; r2 < k; r2++)
        for (long a = 0; a < 6; a++)
            base[r2 * 6 + a] = QR[r2 * nv + a];
    if (!isfinite(squares))
        goto declined;
    split_kernel(QR, k, n, nv - n, wts, res, scr, tol);
    if (res[n + k] != 0.0)
        goto declined;
    double *residual = rv.buf;
    for (long a = 0; a < 6; a++) {
        double t = 0.0;
        for (long r2 = 0; r2 < k; r2++)
            t += base[r2 * 6 + a] * res[n + r2];
        residual[a] = b[a] - t;
    }
    npy_intp dims[1] = {n};
    PyObject *tau = PyArray_SimpleNew(1, dims, NPY_DOUBLE);
    dims[0] = k;
    PyObject *lam = PyArray_SimpleNew(1, dims, NPY_DOUBLE);
    if (tau != NULL && lam != NULL) {
        memcpy(PyArray_DATA((PyArrayObject *)tau), res, sizeof(double) * n);
        memcpy(PyArray_DATA((PyArrayObject *)lam), res + n, sizeof(double) * k);
        out = Py_BuildValue("(NNl)", tau, lam, (long)res[n + k + 1]);
    } else {
        Py_XDECREF(tau);
        Py_XDECREF(lam);
    }
    goto done;
declined:
    out = Py_None;
    Py_INCREF(out);
done:
    PyMem_Free(buf);
release:
    PyBuffer_Release(&pv);
    PyBuffer_Release(&wv);
    PyBuffer_Release(&rv);
    return out;
}

static PyMethodDef split_methods[] = {
    {"split", (PyCFunction)(void (*)(void))c_split, METH_FASTCALL,
     "split(QR, k, wts, res, scr, tol) -> None\n\n"
     "The contact-consistent split of algorithms/split.py: QR holds [J_c^T, b, S^T] by columns\n"
     "((k + 1 + n) x nv, C-contiguous float64, overwritten), wts the n square roots of the\n"
     "weights, tol the rank tolerance relative to J_c's largest row norm; writes tau (n),\n"
     "lambda (k), the status (0 solved, 1 the numpy split's case) and the rank into res;\n"
     "scr is scratch."},
    {"contact", (PyCFunction)(void (*)(void))c_contact, METH_FASTCALL,
     "contact(kernels, q, qd, qdd, gravity, points, wts, tol, residual) -> (tau, lambda, r)\n\n"
     "Contact inverse dynamics of one float64 state of a floating base: M q̈ + h, the contact\n"
     "rows of J_c (points: a row (body, 3 or 6, r_c) a contact), the split of split(), the\n"
     "base residual written into residual (6). None when an argument is not one state, b or\n"
     "J_c is not finite, k < 6, or the split leaves the answer to the numpy split."},
    {NULL, NULL, 0, NULL},
};

/* Add Kernels to the module m, with the generated header's SHA-256 and its WORK (scratch
 * doubles a body). */
int
kernels_add(PyObject *m)
{
    if (PyType_Ready(&KernelsType) < 0)
        return -1;
    Py_INCREF(&KernelsType);
    if (PyModule_AddObject(m, "Kernels", (PyObject *)&KernelsType) < 0) {
        Py_DECREF(&KernelsType);
        return -1;
    }
    if (PyModule_AddFunctions(m, split_methods) < 0
            || PyModule_AddStringConstant(m, "KERNELS_SHA256", KERNELS_SHA256) < 0
            || PyModule_AddIntConstant(m, "WORK", WORK) < 0)
        return -1;
    /* the squared norms of a quaternion the single-state entries take (joints.py's) */
    PyObject *unit = Py_BuildValue("(dd)", UNIT_SQUARED_LOW, UNIT_SQUARED_HIGH);
    if (unit == NULL || PyModule_AddObject(m, "UNIT_SQUARED", unit) < 0) {
        Py_XDECREF(unit);
        return -1;
    }
    return 0;
}

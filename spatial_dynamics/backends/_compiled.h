/* Copyright 2026 spatial_dynamics contributors
 * SPDX-License-Identifier: Apache-2.0
 *
 * What the files of spatial_dynamics.backends._compiled share: private to the extension,
 * never installed. One file a job (_compiled.c says what the extension does as a whole):
 *
 *   _compiled.c   the module: its interface version, and each file's part of it
 *   kernels.c     Kernels, a model's table; one state, or a run of states, through the
 *                 generated kernels (the only file that includes _kernels_generated.h);
 *                 the split, and the contact entry (one state's contact inverse dynamics)
 *   arguments.c   the argument reader: a joint vector or gravity as C doubles (13 item
 *                 types, numpy arrays, buffers, lists, tuples), a C-contiguous float64 table
 *   entries.c     ALGORITHMS, one row per algorithm, and the two generic entries that serve
 *                 them all: one state, and a batch
 *   threads.c     a batch on POSIX threads, a block each claimed chunk by chunk, without
 *                 the GIL
 *   door.c        Door: a public function of spatial_dynamics entered in C for one state
 *
 * Every function declared here is private to the shared object (setup.py compiles with
 * -fvisibility=hidden: only PyInit__compiled is exported), so the calls between the files
 * are plain direct calls.
 */
#ifndef SPATIAL_DYNAMICS_COMPILED_H
#define SPATIAL_DYNAMICS_COMPILED_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

/* The numpy C API, version-targeted: built against numpy 2.x headers, the extension also
 * runs on numpy 1.23 and later (NPY_TARGET_VERSION; 1.23 is the oldest numpy for Python
 * 3.11), e.g. Ubuntu 24.04's 1.26. Built against numpy 1.x headers it runs on numpy 1.x
 * only (numpy's rule); import_array then fails on 2.x and the package runs on plain Python,
 * with compiled.py's warning. One table of the API for all the files: _compiled.c imports it
 * (import_array, with COMPILED_IMPORTS_ARRAY defined), the others use it. */
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#define NPY_TARGET_VERSION NPY_1_23_API_VERSION
#define PY_ARRAY_UNIQUE_SYMBOL spatial_dynamics_compiled_ARRAY_API
#ifndef COMPILED_IMPORTS_ARRAY
#define NO_IMPORT_ARRAY
#endif
#include <numpy/arrayobject.h>

/* Largest count of doubles of one array or scratch: a few such counts add up, and times
 * sizeof(double), without overflow in Py_ssize_t. */
#define MAX_DOUBLES (PY_SSIZE_T_MAX / 64)

/* a x b in *out, or -1 when either is negative or the product exceeds `most`. */
static inline int
checked_mul(Py_ssize_t a, Py_ssize_t b, Py_ssize_t most, Py_ssize_t *out)
{
    if (a < 0 || b < 0 || (a != 0 && b > most / a))
        return -1;
    *out = a * b;
    return 0;
}

/* ------------------------------------------------------------------------------------------
 * kernels.c: a model's table, and the generated kernels run on it */

typedef struct {
    PyObject_HEAD
    double *K;          /* rows x WIDTH, row-major */
    long rows;          /* NB + 1 */
    long n;             /* joints (len(q)) */
    double *zeros;      /* nv zeros: qd, qdd of the terms at rest */
    long nv;            /* velocity coordinates (len(qd), len(tau)); n for a fixed base */
    long quaternion;    /* q[quaternion..+4] the free-flyer's quaternion x y z w, or -1 */
} KernelsObject;

/* The squared norm a free-flyer's quaternion may have, (1 -+ 1e-2)^2: joints.py's
 * QUATERNION_TOLERANCE (the module's UNIT_SQUARED, which a test holds to joints.py's). */
#define UNIT_SQUARED_LOW 0.9801
#define UNIT_SQUARED_HIGH 1.0201

extern PyTypeObject KernelsType;

enum { RNEA = 0, CRBA = 1, MOMENTUM = 2, REGRESSOR = 3, BODIES = 4, DERIVATIVES = 5,
       FORWARD = 6 };  /* the kernels */

/* One batch's job: N states, each through `kernel`; threads.c shares it out in slices of
 * states [lo, hi), kernels.c runs them. */
typedef struct {
    int kernel;
    const double *K;
    long rows, n, nv;                    /* q holds n numbers a state, qd and qdd nv */
    Py_ssize_t size;                     /* doubles of each result of one state */
    const double *q, *qd, *qdd, *fext;  /* (N, n) each or NULL; fext (1 or N, rows, 6) or NULL */
    int fext_per_state;
    double g[3];
    double *out1, *out2, *out3;          /* tau | H | mom, ctq | Y | J | dq, dv, M | qdd */
} Slice;

int result_shape(const KernelsObject *h, int kernel, npy_intp *dims, int *count);
Py_ssize_t work_size(int kernel, long rows, long nv);
int run_state(int kernel, const double *K, long rows, const double *q, const double *qd,
              const double *qdd, const double *g, const double *f, const double *arm,
              double *out1, double *out2, double *out3, double *work);
int run_states(const Slice *s, double *work, Py_ssize_t lo, Py_ssize_t hi);
int kernels_add(PyObject *m);

/* ------------------------------------------------------------------------------------------
 * arguments.c: the argument reader */

/* What as_doubles made of an argument: not one state it reads (the caller's general path
 * then decides), or the numbers, read from float32 or from anything else it reads. */
enum { DECLINED = 0, AS_DOUBLE = 1, AS_FLOAT = 2 };

int as_doubles(PyObject *obj, Py_ssize_t n, double *out);
int get_table(PyObject *obj, Py_buffer *v, int writable, const char *what);

/* ------------------------------------------------------------------------------------------
 * entries.c: the algorithms and their generic entries */

typedef struct {
    const char *name;       /* the single-state entry (and the door's kind: the row) */
    const char *batch;      /* the batch entry, or NULL */
    int vectors;            /* joint vectors it reads: q, then qd, then qdd (the rest zero) */
    int gravity;            /* 3 numbers after them */
    int fext;               /* then, optionally, the external forces (rnea's f_body) */
    int kernel;             /* results: RNEA tau (n,), CRBA H (n, n), MOMENTUM two (n,), */
                            /* REGRESSOR Y (n, 10 NB), BODIES (NB + 1, 16 + 6 n), */
                            /* DERIVATIVES three (n, n): dq, dv, M, */
                            /* FORWARD qdd (n,), reading tau as its third vector */
    const char *outputs[3]; /* the batch entry's result arguments, as its errors name them */
    const char *doc, *batch_doc;
} Algorithm;

extern const Algorithm ALGORITHMS[];
extern const int ALGORITHM_COUNT;

PyObject *single(const Algorithm *a, PyObject *const *args, Py_ssize_t nargs);
int entries_add(PyObject *m);

/* ------------------------------------------------------------------------------------------
 * threads.c: a batch on threads */

int run_batch(const Slice *job, Py_ssize_t N, long threads);
int threads_add(PyObject *m);

/* ------------------------------------------------------------------------------------------
 * door.c: the public functions entered in C */

int door_add(PyObject *m);

#endif

/* Copyright 2026 spatial_dynamics contributors
 * SPDX-License-Identifier: Apache-2.0
 *
 * spatial_dynamics.backends._compiled: the kernels of _kernels_generated.h (generated from
 * spatial_dynamics/algorithms by codegen.py) as a CPython extension, built by setup.py.
 *
 * The extension only moves data, one job a file (_compiled.h lists them and what they
 * share). A Kernels object holds a copy of a model's table (kernels.c). Each algorithm is
 * one row of ALGORITHMS; one generic single-state entry and one generic batch entry serve
 * them all, as the module's functions rnea, mass_matrix, rnea_batch, ... (entries.c). The
 * single-state entries read q, qd, qdd and gravity once each into C doubles from numpy
 * arrays, buffers, lists and tuples, and decline anything else to the Python caller's
 * general path (arguments.c). The batch entries release the GIL and let POSIX threads claim
 * the states chunk by chunk (threads.c); the RNEA of a batch, and its derivatives, run
 * several states at once in the SIMD lanes of _kernels_generated.h. A Door enters a public function of the package in
 * C for one state (door.c). This file is the module: its interface version, and each
 * file's part of it.
 */
#define COMPILED_IMPORTS_ARRAY      /* the numpy C API's table is this file's to import */
#include "_compiled.h"

/* The interface the extension offers to compiled.py, which refuses a build of another (a
 * stale extension left beside newer sources): raise it with every change of an entry. */
#define API 19

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
    PyObject *m = PyModule_Create(&module_def);
    if (m == NULL)
        return NULL;
    if (kernels_add(m) < 0 || entries_add(m) < 0 || threads_add(m) < 0 || door_add(m) < 0
            || PyModule_AddIntConstant(m, "API", API) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}

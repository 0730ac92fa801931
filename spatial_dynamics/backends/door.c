/* Copyright 2026 spatial_dynamics contributors
 * SPDX-License-Identifier: Apache-2.0
 *
 * Door: a public function of spatial_dynamics entered in C.
 *
 * Door(function, kind, kernels, gravity) is called as `function` is (same arguments, and it
 * carries its __doc__, __name__ and __wrapped__); `kind` is the row of `function` in
 * ALGORITHMS (the module's ALGORITHMS names them in order). One state with gravity given or
 * default (`gravity` when not given), no f_ext and backend 'auto' or 'compiled' (and
 * rnea_derivatives' `out` arrays, which its entry writes into or declines), of a model
 * whose Kernels are in the dict `kernels` (id(model) -> Kernels), runs here; every other
 * call, or one whose arguments the entry declines, is passed on to `function` unchanged (it
 * validates, derives the table, runs batches and the other backends). This saves the Python
 * frame of `function` (~0.2 µs, a fifth of a call) on the path users take most. The door
 * keeps the last model it answered (a weak reference) and its Kernels, so that a run of
 * calls on one model skips the dict; when that model is collected, the weak reference's
 * callback lets go of its Kernels.
 */
#include "_compiled.h"

#include <stddef.h>

static PyObject *str_gravity, *str_f_ext, *str_backend, *str_auto, *str_compiled, *str_out;

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
    PyObject *gravity = self->gravity, *f_ext = NULL, *backend = NULL, *out_arrays = NULL;
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
        } else if (a->kernel == DERIVATIVES && is_name(name, str_out)) {
            out_arrays = value;     /* rnea_derivatives' out: the entry takes or declines it */
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
        PyObject *call[7] = {kern, args[1], nv > 1 ? args[2] : NULL, nv > 2 ? args[3] : NULL};
        call[1 + nv] = gravity;
        Py_ssize_t count = 1 + nv + a->gravity;
        if (out_arrays != NULL && out_arrays != Py_None) {     /* then f_body None, out */
            call[count++] = Py_None;
            call[count++] = out_arrays;
        }
        PyObject *out = single(a, call, count);
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

/* Add Door to the module m, with the keywords a door reads. */
int
door_add(PyObject *m)
{
    if (PyType_Ready(&DoorType) < 0)
        return -1;
    str_gravity = PyUnicode_InternFromString("gravity");
    str_f_ext = PyUnicode_InternFromString("f_ext");
    str_backend = PyUnicode_InternFromString("backend");
    str_auto = PyUnicode_InternFromString("auto");
    str_compiled = PyUnicode_InternFromString("compiled");
    str_out = PyUnicode_InternFromString("out");
    if (!(str_gravity && str_f_ext && str_backend && str_auto && str_compiled && str_out))
        return -1;
    Py_INCREF(&DoorType);
    if (PyModule_AddObject(m, "Door", (PyObject *)&DoorType) < 0) {
        Py_DECREF(&DoorType);
        return -1;
    }
    return 0;
}

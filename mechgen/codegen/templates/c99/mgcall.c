/*
 * mgcall: near-zero-overhead calls of generated mechgen kernels from Python.
 *
 * A fixed C source (not a template), compiled by mechgen.codegen.build into
 * the compile cache and imported as the extension module "mgcall".
 *
 * Input:  bind(fn_address, in_ptrs, out_ptrs, sizes, nbatch, keepalive)
 *         fn_address: address of a kernel with the mechgen ABI
 *             int NAME(const double *const *in, double *const *out,
 *                      const long *sizes, long nbatch);
 *         in_ptrs, out_ptrs: sequences of int (addresses of contiguous
 *             float64 arrays), sizes: sequence of int, nbatch: int >= 0,
 *         keepalive: any object (the arrays and the library), referenced
 *             for as long as the bound call lives.
 * Output: a Bound object; calling it with no arguments calls the kernel with
 *         the stored pointers and returns the int the kernel returned.
 *
 * Bound uses the vectorcall protocol, so a call costs tens of nanoseconds.
 * The GIL is held during the call (kernels are short and touch only the
 * arrays kept alive by keepalive).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#ifndef Py_TPFLAGS_HAVE_VECTORCALL
#define Py_TPFLAGS_HAVE_VECTORCALL _Py_TPFLAGS_HAVE_VECTORCALL
#endif

typedef int (*mg_kernel)(const double *const *in, double *const *out, const long *sizes, long nbatch);

typedef struct {
    PyObject_HEAD
    vectorcallfunc vectorcall;
    mg_kernel fn;
    double **in;
    double **out;
    long *sizes;
    long nbatch;
    Py_ssize_t nin;
    Py_ssize_t nout;
    Py_ssize_t nsizes;
    PyObject *keepalive;
} BoundObject;

static PyObject *
Bound_vectorcall(PyObject *self, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    BoundObject *b = (BoundObject *)self;
    int rc;
    (void)args;
    if (PyVectorcall_NARGS(nargsf) != 0 || (kwnames != NULL && PyTuple_GET_SIZE(kwnames) != 0)) {
        PyErr_SetString(PyExc_TypeError, "a bound kernel takes no arguments");
        return NULL;
    }
    rc = b->fn((const double *const *)b->in, (double *const *)b->out, b->sizes, b->nbatch);
    return PyLong_FromLong((long)rc);
}

static int
Bound_traverse(PyObject *self, visitproc visit, void *arg)
{
    Py_VISIT(((BoundObject *)self)->keepalive);
    return 0;
}

static int
Bound_clear(PyObject *self)
{
    Py_CLEAR(((BoundObject *)self)->keepalive);
    return 0;
}

static void
Bound_dealloc(PyObject *self)
{
    BoundObject *b = (BoundObject *)self;
    PyObject_GC_UnTrack(self);
    Bound_clear(self);
    free(b->in);
    free(b->out);
    free(b->sizes);
    Py_TYPE(self)->tp_free(self);
}

static PyObject *
Bound_repr(PyObject *self)
{
    BoundObject *b = (BoundObject *)self;
    return PyUnicode_FromFormat("<mgcall.Bound %zd in, %zd out, %zd sizes, nbatch=%ld>",
                                b->nin, b->nout, b->nsizes, b->nbatch);
}

static PyTypeObject BoundType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "mgcall.Bound",
    .tp_doc = "A kernel call with stored pointers; call it with no arguments.",
    .tp_basicsize = sizeof(BoundObject),
    .tp_itemsize = 0,
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_vectorcall_offset = offsetof(BoundObject, vectorcall),
    .tp_call = PyVectorcall_Call,
    .tp_traverse = Bound_traverse,
    .tp_clear = Bound_clear,
    .tp_dealloc = Bound_dealloc,
    .tp_repr = Bound_repr,
};

/* Copy a sequence of Python ints into a new malloc'ed array of pointers. */
static double **
pointer_array(PyObject *seq, const char *what, Py_ssize_t *count)
{
    PyObject *fast = PySequence_Fast(seq, what);
    Py_ssize_t i, n;
    double **arr;
    if (fast == NULL)
        return NULL;
    n = PySequence_Fast_GET_SIZE(fast);
    arr = (double **)malloc((size_t)(n > 0 ? n : 1) * sizeof(double *));
    if (arr == NULL) {
        Py_DECREF(fast);
        PyErr_NoMemory();
        return NULL;
    }
    for (i = 0; i < n; i++) {
        void *p = PyLong_AsVoidPtr(PySequence_Fast_GET_ITEM(fast, i));
        if (p == NULL && PyErr_Occurred()) {
            free(arr);
            Py_DECREF(fast);
            return NULL;
        }
        arr[i] = (double *)p;
    }
    Py_DECREF(fast);
    *count = n;
    return arr;
}

/* Copy a sequence of Python ints into a new malloc'ed array of longs. */
static long *
long_array(PyObject *seq, const char *what, Py_ssize_t *count)
{
    PyObject *fast = PySequence_Fast(seq, what);
    Py_ssize_t i, n;
    long *arr;
    if (fast == NULL)
        return NULL;
    n = PySequence_Fast_GET_SIZE(fast);
    arr = (long *)malloc((size_t)(n > 0 ? n : 1) * sizeof(long));
    if (arr == NULL) {
        Py_DECREF(fast);
        PyErr_NoMemory();
        return NULL;
    }
    for (i = 0; i < n; i++) {
        long v = PyLong_AsLong(PySequence_Fast_GET_ITEM(fast, i));
        if (v == -1 && PyErr_Occurred()) {
            free(arr);
            Py_DECREF(fast);
            return NULL;
        }
        arr[i] = v;
    }
    Py_DECREF(fast);
    *count = n;
    return arr;
}

static PyObject *
mgcall_bind(PyObject *module, PyObject *args, PyObject *kwargs)
{
    static char *kwlist[] = {"fn_address", "in_ptrs", "out_ptrs", "sizes", "nbatch", "keepalive", NULL};
    PyObject *address, *in_seq, *out_seq, *size_seq, *keepalive;
    long nbatch;
    void *fn;
    BoundObject *b;
    (void)module;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OOOOlO:bind", kwlist, &address, &in_seq, &out_seq,
                                     &size_seq, &nbatch, &keepalive))
        return NULL;
    fn = PyLong_AsVoidPtr(address);
    if (fn == NULL) {
        if (!PyErr_Occurred())
            PyErr_SetString(PyExc_ValueError, "bind: fn_address is NULL");
        return NULL;
    }
    if (nbatch < 0) {
        PyErr_SetString(PyExc_ValueError, "bind: nbatch must be >= 0");
        return NULL;
    }
    b = PyObject_GC_New(BoundObject, &BoundType);
    if (b == NULL)
        return NULL;
    b->vectorcall = Bound_vectorcall;
    b->fn = (mg_kernel)(uintptr_t)fn;
    b->in = NULL;
    b->out = NULL;
    b->sizes = NULL;
    b->nbatch = nbatch;
    b->nin = b->nout = b->nsizes = 0;
    Py_INCREF(keepalive);
    b->keepalive = keepalive;
    PyObject_GC_Track((PyObject *)b);
    b->in = pointer_array(in_seq, "bind: in_ptrs must be a sequence of int", &b->nin);
    if (b->in == NULL)
        goto fail;
    b->out = pointer_array(out_seq, "bind: out_ptrs must be a sequence of int", &b->nout);
    if (b->out == NULL)
        goto fail;
    b->sizes = long_array(size_seq, "bind: sizes must be a sequence of int", &b->nsizes);
    if (b->sizes == NULL)
        goto fail;
    return (PyObject *)b;
fail:
    Py_DECREF(b);
    return NULL;
}

static PyMethodDef mgcall_methods[] = {
    {"bind", (PyCFunction)(void (*)(void))mgcall_bind, METH_VARARGS | METH_KEYWORDS,
     "bind(fn_address, in_ptrs, out_ptrs, sizes, nbatch, keepalive) -> Bound\n\n"
     "Prepare a call of the kernel at fn_address with the given pointers."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef mgcall_module = {
    PyModuleDef_HEAD_INIT,
    .m_name = "mgcall",
    .m_doc = "Near-zero-overhead calls of mechgen kernels (vectorcall).",
    .m_size = -1,
    .m_methods = mgcall_methods,
};

PyMODINIT_FUNC
PyInit_mgcall(void)
{
    PyObject *m;
    if (PyType_Ready(&BoundType) < 0)
        return NULL;
    m = PyModule_Create(&mgcall_module);
    if (m == NULL)
        return NULL;
    Py_INCREF(&BoundType);
    if (PyModule_AddObject(m, "Bound", (PyObject *)&BoundType) < 0) {
        Py_DECREF(&BoundType);
        Py_DECREF(m);
        return NULL;
    }
    return m;
}

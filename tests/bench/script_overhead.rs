//! Scripting overhead: native API calls per second from Rhai (`translate` + `aabb` on
//! a component) against the same loop in Python 3 calling an equivalent native method
//! (a C extension written here, compiled at bench time, doing the same work: add a
//! translation, return `{"min": [..], "max": [..]}` from the cached rotated box).
//! Run with `cargo bench --bench script_overhead`.

use std::path::Path;
use std::process::Command;

#[path = "rhai_timing.rs"]
mod rhai_timing;

const N: usize = 200_000;

/// The script `body` after the setup lines (a document and a component).
fn rhai_seconds(dir: &Path, body: &str) -> f64 {
    rhai_timing::rhai_seconds(
        dir,
        &format!(
            "let d = open_doc(\"models/cell.yaml\");\nlet s = d.component(\"screw4\");\n{body}\n"
        ),
    )
}

const C_SOURCE: &str = r#"
#define PY_SSIZE_T_CLEAN
#include <Python.h>
typedef struct { PyObject_HEAD double t[3]; double lo[3], hi[3]; } Comp;
static PyObject* translate(Comp* s, PyObject* const* a, Py_ssize_t n) {
    if (n != 3) { PyErr_SetString(PyExc_TypeError, "translate(dx, dy, dz)"); return NULL; }
    for (int i = 0; i < 3; i++) { double v = PyFloat_AsDouble(a[i]); if (v == -1.0 && PyErr_Occurred()) return NULL; s->t[i] += v; }
    Py_RETURN_NONE;
}
static PyObject* vec(double* v, double* t) { return Py_BuildValue("[ddd]", v[0] + t[0], v[1] + t[1], v[2] + t[2]); }
static PyObject* aabb(Comp* s, PyObject* unused) {
    PyObject* d = PyDict_New(); PyObject* mn = vec(s->lo, s->t); PyObject* mx = vec(s->hi, s->t);
    PyDict_SetItemString(d, "min", mn); PyDict_SetItemString(d, "max", mx); Py_DECREF(mn); Py_DECREF(mx); return d;
}
static int init(Comp* s, PyObject* args, PyObject* kw) {
    return PyArg_ParseTuple(args, "dddddd", &s->lo[0], &s->lo[1], &s->lo[2], &s->hi[0], &s->hi[1], &s->hi[2]) ? 0 : -1;
}
static PyMethodDef methods[] = {
    {"translate", (PyCFunction)(void(*)(void))translate, METH_FASTCALL, ""},
    {"aabb", (PyCFunction)aabb, METH_NOARGS, ""}, {NULL}};
static PyTypeObject CompType = { PyVarObject_HEAD_INIT(NULL, 0) .tp_name = "fitupbench.Component",
    .tp_basicsize = sizeof(Comp), .tp_flags = Py_TPFLAGS_DEFAULT, .tp_new = PyType_GenericNew,
    .tp_init = (initproc)init, .tp_methods = methods };
static struct PyModuleDef mod = { PyModuleDef_HEAD_INIT, "fitupbench", NULL, -1, NULL };
PyMODINIT_FUNC PyInit_fitupbench(void) {
    if (PyType_Ready(&CompType) < 0) return NULL;
    PyObject* m = PyModule_Create(&mod); Py_INCREF(&CompType);
    PyModule_AddObject(m, "Component", (PyObject*)&CompType); return m;
}
"#;

fn python_seconds(dir: &Path, body: &str) -> Option<f64> {
    let code = format!(
        "import sys, time\nsys.path.insert(0, {dir:?})\nimport fitupbench\ns = fitupbench.Component(-7.0, -7.0, 0.0, 7.0, 7.0, 15.0)\nN = {N}\nt = time.perf_counter()\n{body}\nprint(time.perf_counter() - t)\n",
        dir = dir.to_string_lossy()
    );
    let out = Command::new("python3").arg("-c").arg(code).output().ok()?;
    String::from_utf8_lossy(&out.stdout).trim().parse().ok()
}

fn build_extension(dir: &Path) -> bool {
    let cfg = |k: &str| -> Option<String> {
        let o = Command::new("python3").args(["-c", &format!("import sysconfig; print(sysconfig.get_config_var('{k}') or sysconfig.get_paths().get('{k}', ''))")]).output().ok()?;
        Some(String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let (Some(inc), Some(suffix)) = (cfg("include"), cfg("EXT_SUFFIX")) else {
        return false;
    };
    std::fs::write(dir.join("fitupbench.c"), C_SOURCE).unwrap();
    Command::new("cc")
        .args(["-O2", "-shared", "-fPIC", "-I", &inc, "-o"])
        .arg(dir.join(format!("fitupbench{suffix}")))
        .arg(dir.join("fitupbench.c"))
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let dir = tempfile::tempdir().unwrap();
    fitup::demo::write_cell(&dir.path().join("models")).unwrap();
    std::fs::create_dir(dir.path().join("scripts")).unwrap();
    let py_ok = build_extension(dir.path());
    let rhai_api = format!("for i in 0..{N} {{ s.translate(0.001, 0.0, 0.0); let b = s.aabb(); }}");
    let rhai_empty = format!("for i in 0..{N} {{ let a = 0.001; let b = i; }}");
    let py_api = "for i in range(N):\n    s.translate(0.001, 0.0, 0.0)\n    b = s.aabb()";
    let py_empty = "for i in range(N):\n    a = 0.001\n    b = i";
    let (mut ra, mut re, mut pa, mut pe) = (vec![], vec![], vec![], vec![]);
    for _round in 0..10 {
        ra.push(rhai_seconds(dir.path(), &rhai_api));
        re.push(rhai_seconds(dir.path(), &rhai_empty));
        if py_ok {
            pa.extend(python_seconds(dir.path(), py_api));
            pe.extend(python_seconds(dir.path(), py_empty));
        }
    }
    let per_call = |api: f64, empty: f64| (api - empty) / (2 * N) as f64 * 1e9;
    let (ra, re) = (median(&mut ra), median(&mut re));
    println!("Rhai:   loop {:.0} ns/iter, empty loop {:.0} ns/iter → {:.0} ns per API call ({:.2} M calls/s)", ra / N as f64 * 1e9, re / N as f64 * 1e9, per_call(ra, re), 1e3 / per_call(ra, re));
    if pa.is_empty() {
        println!("Python: not measured (python3 or a C compiler is missing)");
    } else {
        let (pa, pe) = (median(&mut pa), median(&mut pe));
        println!("Python: loop {:.0} ns/iter, empty loop {:.0} ns/iter → {:.0} ns per native call ({:.2} M calls/s)", pa / N as f64 * 1e9, pe / N as f64 * 1e9, per_call(pa, pe), 1e3 / per_call(pa, pe));
        println!(
            "ratio Rhai / Python per call: {:.2}",
            per_call(ra, re) / per_call(pa, pe)
        );
    }
    println!(
        "loadavg: {}",
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
}

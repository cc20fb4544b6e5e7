/* The successor generation of paper 003's walking problem, compiled.
 *
 * Source of the method: Ondroušek & Březina (paper 003), the production rules 1-27 as written
 * in Python in rules.py and model.py (WalkProblem.body_moves, WalkProblem.leg_options,
 * heading_error, rotation_limit, translation_limit, _liftable) and the quick terrain tests of
 * terrain.py. This file repeats that Python arithmetic operation for operation, so its
 * results are the same floats, the same keys and the same lists: hypot is Python's own
 * math.hypot (called, not reimplemented), round() is round-half-even (nearbyint), and a float
 * % is Python's (the sign of the divisor). The detailed body sweeps of Terrain.translation_ok
 * and Terrain.rotation_ok (numpy in Python) are repeated too: the poses as numpy.linspace
 * computes them, cos/sin of the C library (numpy's float64 cos/sin on the machines tested;
 * the tests compare), rint as nearbyint. tests/studies/quadruped_plan/test_walkcore.py
 * checks every successor of many states, and the sweeps, against the Python code.
 *
 * Not covered (the Python code runs instead): the exclusion zone, the body shifts 28-31.
 * A state with a NaN or infinite value is refused (ValueError; the Python code fails on most
 * of them too, with a ValueError or OverflowError).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <string.h>

#define KEY_FIELDS 11
#define KEY_BITS 40
#define FIELD_MAX (((int64_t)1) << (KEY_BITS - 1))

typedef struct {
    PyObject_HEAD
    /* model (QuadrupedModel._trans, ._rot and constants) */
    double hx[4], hy[4], side[4];
    double rot_h[4], rot_th[4], rot_out[4], rot_in[4], wedge_c[4][2], wedge_nh[4][2];
    double cot, lmax, lmin, b3, eps, workspace_tol, min_move, stable, lmax2;
    /* the problem */
    double gx, gy, q, angle_grid;
    int sense, set_b;
    double fixed[4][2][2]; /* per leg: rules 4+leg, 8+leg -> (fx, fy) */
    double unit_max[4][2], unit_min[4][2];
    /* the terrain (or none) */
    PyObject *terrain;
    Py_buffer views[3]; /* body, foot, outline: held until dealloc (no resize meanwhile) */
    int nviews, initialised, tried;
    const double *body, *foot;
    double tx0, ty0, inv, r_hip, body_thr, foot_thr, r_robot, half_a, half_b, spacing, quick;
    Py_ssize_t nx, ny, n_outline;
    const double *outline; /* the body outline's sample points in the body frame [k, 2] */
    /* Python objects used */
    PyObject *hypot, *key_offset, *shift[KEY_FIELDS], *one;
} WalkCore;

static const double TWO_PI = 2.0 * 3.14159265358979323846;
static const double PI = 3.14159265358979323846;

/* Python's float %: the result has the sign of the divisor */
static double py_mod(double x, double y) {
    double m = fmod(x, y);
    if (m != 0.0) {
        if ((y < 0.0) != (m < 0.0)) m += y;
    } else {
        m = copysign(0.0, y);
    }
    return m;
}

static int py_hypot(WalkCore *c, double x, double y, double *out) {
    PyObject *args[2];
    args[0] = PyFloat_FromDouble(x);
    args[1] = PyFloat_FromDouble(y);
    if (!args[0] || !args[1]) { Py_XDECREF(args[0]); Py_XDECREF(args[1]); return -1; }
    PyObject *r = PyObject_Vectorcall(c->hypot, args, 2, NULL);
    Py_DECREF(args[0]);
    Py_DECREF(args[1]);
    if (!r) return -1;
    *out = PyFloat_AsDouble(r);
    Py_DECREF(r);
    return 0;
}

static int read_state(PyObject *s, double v[11]) {
    if (!PyTuple_Check(s) || PyTuple_GET_SIZE(s) < 12) {
        PyErr_SetString(PyExc_TypeError, "expected a state tuple (11 floats and the key)");
        return -1;
    }
    for (int i = 0; i < 11; i++) {
        PyObject *o = PyTuple_GET_ITEM(s, i);
        v[i] = PyFloat_AsDouble(o);
        if (v[i] == -1.0 && PyErr_Occurred()) return -1;
        if (!isfinite(v[i])) { /* the Python successors fail with a ValueError too */
            PyErr_Format(PyExc_ValueError, "state: expected finite numbers, got %R", o);
            return -1;
        }
    }
    return 0;
}

/* ---- the key (rules.WalkProblem._with_key) ---------------------------------------------- */

/* sum of idx[i] << (KEY_BITS i) plus the offset, as a Python int */
static PyObject *make_key(WalkCore *c, const double idx[KEY_FIELDS]) {
    int fast = 1;
    for (int i = 0; i < KEY_FIELDS; i++)
        if (!(idx[i] > -(double)FIELD_MAX && idx[i] < (double)FIELD_MAX)) fast = 0;
    if (fast) { /* fields idx + 2^39 in [0, 2^40): 55 little-endian bytes, no carries */
        unsigned char buf[KEY_FIELDS * KEY_BITS / 8];
        memset(buf, 0, sizeof buf);
        for (int i = 0; i < KEY_FIELDS; i++) {
            uint64_t f = (uint64_t)((int64_t)idx[i] + FIELD_MAX);
            for (int b = 0; b < KEY_BITS / 8; b++) buf[i * 5 + b] = (unsigned char)(f >> (8 * b));
        }
#if PY_VERSION_HEX >= 0x030D0000
        return PyLong_FromUnsignedNativeBytes(buf, sizeof buf,
                                              Py_ASNATIVEBYTES_LITTLE_ENDIAN
                                                  | Py_ASNATIVEBYTES_UNSIGNED_BUFFER);
#else
        return _PyLong_FromByteArray(buf, sizeof buf, 1, 0);
#endif
    }
    PyObject *acc = c->key_offset;
    Py_INCREF(acc);
    for (int i = 0; i < KEY_FIELDS; i++) {
        PyObject *t = PyLong_FromDouble(idx[i]);
        if (!t) { Py_DECREF(acc); return NULL; }
        PyObject *sh = PyNumber_Lshift(t, c->shift[i]);
        Py_DECREF(t);
        if (!sh) { Py_DECREF(acc); return NULL; }
        PyObject *n = PyNumber_Add(acc, sh);
        Py_DECREF(sh);
        Py_DECREF(acc);
        if (!n) return NULL;
        acc = n;
    }
    return acc;
}

/* the state tuple (v[0..10], key) */
static PyObject *with_key(WalkCore *c, const double v[11]) {
    double idx[KEY_FIELDS];
    for (int i = 0; i < 11; i++) idx[i] = nearbyint(v[i] * c->q);
    idx[2] = nearbyint(py_mod(v[2], TWO_PI) / c->angle_grid);
    PyObject *key = make_key(c, idx);
    if (!key) return NULL;
    PyObject *t = PyTuple_New(12);
    if (!t) { Py_DECREF(key); return NULL; }
    for (int i = 0; i < 11; i++) {
        PyObject *f = PyFloat_FromDouble(v[i]);
        if (!f) { Py_DECREF(t); Py_DECREF(key); return NULL; }
        PyTuple_SET_ITEM(t, i, f);
    }
    PyTuple_SET_ITEM(t, 11, key);
    return t;
}

/* ---- geometry (model.py) ----------------------------------------------------------------- */

static double heading_error(WalkCore *c, const double s[11]) {
    double bearing = atan2(c->gy - s[1], c->gx - s[0]);
    double heading = c->sense < 0 ? s[2] - PI / 2 : s[2] + PI / 2;
    double diff = py_mod(bearing - heading + PI, 2 * PI) - PI;
    if (c->sense == 0 && fabs(diff) > PI / 2) diff = diff > 0 ? diff - PI : diff + PI;
    return diff;
}

/* math.sqrt: a ValueError below 0 (returns -1 with the error set) */
static int py_sqrt(double x, double *out) {
    if (x < 0.0) {
        PyErr_SetString(PyExc_ValueError, "math domain error");
        return -1;
    }
    *out = sqrt(x);
    return 0;
}

/* the limit in *out; -1 with a Python error set where math.sqrt would raise */
static int translation_limit(WalkCore *c, const double s[11], double sign, double *out) {
    double best = INFINITY;
    for (int i = 0; i < 4; i++) {
        int j = 3 + 2 * i;
        double ux = c->side[i] * (s[j] - c->hx[i]);
        double ry = sign * (s[j + 1] - c->hy[i]);
        double t = ry + ux * c->cot;
        double r = c->lmax2 - ux * ux;
        double u = r > 0 ? ry + sqrt(r) : ry;
        if (u < t) t = u;
        if (ux < c->lmin - c->workspace_tol && ry > 0) {
            double root;
            if (py_sqrt(c->lmin * c->lmin - ux * ux, &root)) return -1;
            u = ry - root;
            if (u < t) t = u;
        }
        if (t < best) best = t;
    }
    *out = best > 0.0 ? best : 0.0;
    return 0;
}

static double rotation_limit(WalkCore *c, const double s[11], double direction) {
    double move = -direction, best = INFINITY;
    for (int i = 0; i < 4; i++) {
        double px = s[3 + 2 * i], py = s[4 + 2 * i];
        double r2 = px * px + py * py;
        if (r2 < c->eps * c->eps) return 0.0;
        double r = sqrt(r2), theta = atan2(py, px), h = c->rot_h[i], th = c->rot_th[i], k, v;
        k = (r2 + c->rot_out[i]) / (2 * r * h);
        if (k > -1.0) {
            v = acos(k < 1.0 ? k : 1.0) - move * (py_mod(theta - th + PI, TWO_PI) - PI);
            if (v < best) best = v;
        }
        k = (r2 + c->rot_in[i]) / (2 * r * h);
        if (k < 1.0) {
            v = TWO_PI - acos(k > -1.0 ? k : -1.0) - py_mod(move * (theta - th), TWO_PI);
            if (v < best) best = v;
        }
        for (int w = 0; w < 2; w++) {
            k = c->wedge_nh[i][w] / r;
            if (k > -1.0) {
                v = acos(k < 1.0 ? k : 1.0)
                    - move * (py_mod(theta - c->wedge_c[i][w] + PI, TWO_PI) - PI);
                if (v < best) best = v;
            }
        }
        if (best <= 0.0) return 0.0;
    }
    return best;
}

static double tri(double e1, double e2, double e3, double l1, double l2, double l3) {
    double orient = e1 + e2 + e3;
    if (orient == 0 || l1 == 0 || l2 == 0 || l3 == 0) return -INFINITY;
    double d1 = e1 / l1, d2 = e2 / l2, d3 = e3 / l3, m;
    if (orient > 0) {
        m = d1 < d2 ? d1 : d2;
        return m < d3 ? m : d3;
    }
    m = d1 > d2 ? d1 : d2;
    return -(m > d3 ? m : d3);
}

static int liftable(WalkCore *c, const double s[11], int lift[4]) {
    double ax = s[3], ay = s[4], bx = s[5], by = s[6], cx = s[7], cy = s[8], dx = s[9],
           dy = s[10];
    double ab = ax * by - ay * bx, bc = bx * cy - by * cx, cd = cx * dy - cy * dx,
           da = dx * ay - dy * ax, ac = ax * cy - ay * cx, bd = bx * dy - by * dx;
    double lab, lbc, lcd, lda, lac, lbd;
    if (py_hypot(c, bx - ax, by - ay, &lab) || py_hypot(c, cx - bx, cy - by, &lbc)
        || py_hypot(c, dx - cx, dy - cy, &lcd) || py_hypot(c, ax - dx, ay - dy, &lda)
        || py_hypot(c, cx - ax, cy - ay, &lac) || py_hypot(c, dx - bx, dy - by, &lbd))
        return -1;
    lift[0] = tri(bc, cd, -bd, lbc, lcd, lbd) >= c->stable;
    lift[1] = tri(cd, da, ac, lcd, lda, lac) >= c->stable;
    lift[2] = tri(da, ab, bd, lda, lab, lbd) >= c->stable;
    lift[3] = tri(ab, bc, -ac, lab, lbc, lac) >= c->stable;
    return 0;
}

/* ---- the terrain's quick tests (terrain.py) ---------------------------------------------- */

static int grid_index(WalkCore *c, double x, double y, Py_ssize_t *k) {
    double fi = (x - c->tx0) * c->inv + 0.5, fj = (y - c->ty0) * c->inv + 0.5;
    /* Python's int() truncates towards zero; out-of-range values fail the bounds test */
    if (!(fi > -1.0 && fj > -1.0 && fi < (double)c->nx + 1.0 && fj < (double)c->ny + 1.0))
        return 0;
    Py_ssize_t i = (Py_ssize_t)fi, j = (Py_ssize_t)fj;
    if (i < 0 || j < 0 || i >= c->nx || j >= c->ny) return 0;
    *k = i * c->ny + j;
    return 1;
}

static double body_distance(WalkCore *c, double x, double y) {
    Py_ssize_t k;
    return grid_index(c, x, y, &k) ? c->body[k] : -1.0;
}

static int foot_ok(WalkCore *c, double x, double y) {
    Py_ssize_t k;
    return grid_index(c, x, y, &k) && c->foot[k] >= c->foot_thr;
}

/* numpy.linspace(0.0, stop, n) as numpy computes it (arange * step, the last = stop) */
static void linspace0(double stop, Py_ssize_t n, double *out) {
    if (n == 1) { out[0] = 0.0 * stop + 0.0; return; }
    double div = (double)(n - 1), step = stop / div;
    for (Py_ssize_t i = 0; i < n; i++)
        out[i] = (step == 0.0 ? ((double)i / div) * stop : (double)i * step) + 0.0;
    out[n - 1] = stop;
}

/* Terrain._sweep_clear: the body outline at every pose clear (grid lookups, rint as numpy)
 * and no obstacle vertex inside the body; 1 clear, 0 blocked, -1 error */
static int sweep_clear(WalkCore *c, const double *xs, const double *ys, const double *phis,
                       Py_ssize_t n) {
    for (Py_ssize_t p = 0; p < n; p++) {
        double cs = cos(phis[p]), sn = sin(phis[p]);
        for (Py_ssize_t k = 0; k < c->n_outline; k++) {
            double lx = c->outline[2 * k], ly = c->outline[2 * k + 1];
            double fi = nearbyint((xs[p] + (cs * lx - sn * ly) - c->tx0) * c->inv);
            double fj = nearbyint((ys[p] + (sn * lx + cs * ly) - c->ty0) * c->inv);
            if (!(fi >= 0 && fj >= 0 && fi < (double)c->nx && fj < (double)c->ny)) return 0;
            if (!(c->body[(Py_ssize_t)(fi * (double)c->ny + fj)] >= c->body_thr)) return 0;
        }
    }
    PyObject *verts = PyObject_GetAttrString(c->terrain, "_verts");
    if (!verts) return -1;
    Py_buffer v;
    if (PyObject_GetBuffer(verts, &v, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT)) {
        Py_DECREF(verts);
        return -1;
    }
    int clear = 1;
    if (v.itemsize != 8 || !v.format || strcmp(v.format, "d") != 0 || v.len % 16) {
        PyErr_SetString(PyExc_ValueError, "terrain vertices: expected float64 [n, 2]");
        clear = -1;
    }
    const double *vp = (const double *)v.buf;
    Py_ssize_t nv = clear > 0 ? v.len / 16 : 0;
    for (Py_ssize_t p = 0; p < n && clear > 0; p++) {
        double cs = cos(phis[p]), sn = sin(phis[p]);
        for (Py_ssize_t k = 0; k < nv; k++) {
            double dx = vp[2 * k] - xs[p], dy = vp[2 * k + 1] - ys[p];
            double u = cs * dx + sn * dy, w = -sn * dx + cs * dy;
            if (fabs(u) < c->half_a && fabs(w) < c->half_b) { clear = 0; break; }
        }
    }
    PyBuffer_Release(&v);
    Py_DECREF(verts);
    return clear;
}

/* the poses of a translation (x + t dx, y + t dy, phi) or a rotation (x, y, phi + t) */
static int sweep_poses(WalkCore *c, Py_ssize_t n, const double *t, int rotate, double x,
                       double dx, double y, double dy, double phi) {
    double *buf = PyMem_Malloc(3 * (size_t)n * sizeof(double));
    if (!buf) { PyErr_NoMemory(); return -1; }
    double *xs = buf, *ys = buf + n, *phis = buf + 2 * n;
    for (Py_ssize_t i = 0; i < n; i++) {
        xs[i] = rotate ? x : x + t[i] * dx;
        ys[i] = rotate ? y : y + t[i] * dy;
        phis[i] = rotate ? phi + t[i] : phi;
    }
    int r = sweep_clear(c, xs, ys, phis, n);
    PyMem_Free(buf);
    return r;
}

/* 1 clear, 0 blocked, -1 error (Terrain.rotation_ok) */
static int rotation_ok(WalkCore *c, const double s[11], double turn) {
    if (body_distance(c, s[0], s[1]) >= c->r_hip + c->body_thr) return 1;
    double nd = ceil(fabs(turn) * c->r_hip / c->spacing) + 1.0;
    if (!(nd >= 1.0 && nd < 1e6)) { PyErr_SetString(PyExc_ValueError, "turn"); return -1; }
    Py_ssize_t n = (Py_ssize_t)nd;
    double *t = PyMem_Malloc((size_t)n * sizeof(double));
    if (!t) { PyErr_NoMemory(); return -1; }
    linspace0(turn, n, t); /* the poses' angles: s[2] + linspace(0, turn, n) */
    int r = sweep_poses(c, n, t, 1, s[0], 0.0, s[1], 0.0, s[2]);
    PyMem_Free(t);
    return r;
}

/* Terrain.translation_ok: the quick disc test, then the sweep */
static int translation_ok(WalkCore *c, const double s[11], double nx, double ny) {
    double d;
    if (py_hypot(c, nx - s[0], ny - s[1], &d)) return -1;
    double kd = ceil(d / c->quick);
    if (!(kd >= 0.0 && kd < 1e6)) { PyErr_SetString(PyExc_ValueError, "distance"); return -1; }
    long long k = (long long)kd;
    double kk = k > 1 ? (double)k : 1.0;
    double r = c->r_hip + 0.5 * d / kk + c->body_thr, x = s[0], y = s[1], dx = nx - s[0],
           dy = ny - s[1];
    long long i;
    for (i = 0; i <= k; i++) {
        Py_ssize_t g;
        if (!grid_index(c, x + dx * (double)i / kk, y + dy * (double)i / kk, &g)
            || c->body[g] < r)
            break;
    }
    if (i > k) return 1;
    double nd = ceil(d / c->spacing) + 1.0;
    if (!(nd >= 1.0 && nd < 1e6)) { PyErr_SetString(PyExc_ValueError, "distance"); return -1; }
    Py_ssize_t n = (Py_ssize_t)nd;
    double *t = PyMem_Malloc((size_t)n * sizeof(double));
    if (!t) { PyErr_NoMemory(); return -1; }
    linspace0(1.0, n, t);
    int res = sweep_poses(c, n, t, 0, x, dx, y, dy, s[2]);
    PyMem_Free(t);
    return res;
}

/* ---- body moves (WalkProblem.body_moves) ------------------------------------------------- */

static int append_move(PyObject *out, long rule, PyObject *child) {
    if (!child) return -1;
    PyObject *item = Py_BuildValue("(lNd)", rule, child, 1.0);
    if (!item) return -1;
    int rc = PyList_Append(out, item);
    Py_DECREF(item);
    return rc;
}

/* the translated child, Py_None when the terrain refuses it, NULL on error */
static PyObject *translate(WalkCore *c, const double s[11], double dist) {
    double cs = cos(s[2]), sn = sin(s[2]);
    double nx = s[0] - sn * dist, ny = s[1] + cs * dist;
    if (c->terrain) {
        int ok = translation_ok(c, s, nx, ny);
        if (ok < 0) return NULL;
        if (!ok) Py_RETURN_NONE;
    }
    double v[11] = {nx, ny, s[2], s[3], s[4] - dist, s[5], s[6] - dist, s[7], s[8] - dist,
                    s[9], s[10] - dist};
    return with_key(c, v);
}

static int ready(WalkCore *c) {
    if (c->initialised) return 1;
    PyErr_SetString(PyExc_RuntimeError, "WalkCore was not initialised");
    return 0;
}

static PyObject *WalkCore_body_moves(WalkCore *c, PyObject *state) {
    double s[11];
    if (!ready(c) || read_state(state, s)) return NULL;
    PyObject *out = PyList_New(0);
    if (!out) return NULL;
    double delta = heading_error(c, s);
    if (fabs(delta) > c->min_move) {
        double direction = delta > 0 ? 1.0 : -1.0;
        double lim = rotation_limit(c, s, direction), a = fabs(delta);
        double turn = direction * (lim < a ? lim : a);
        if (fabs(turn) > c->min_move) {
            int ok = c->terrain ? rotation_ok(c, s, turn) : 1;
            if (ok < 0) goto fail;
            if (ok) {
                double cs = cos(turn), sn = sin(turn), v[11];
                v[0] = s[0]; v[1] = s[1]; v[2] = s[2] + turn;
                for (int i = 0; i < 4; i++) {
                    double px = s[3 + 2 * i], py = s[4 + 2 * i];
                    v[3 + 2 * i] = cs * px + sn * py;
                    v[4 + 2 * i] = -sn * px + cs * py;
                }
                if (append_move(out, 1, with_key(c, v))) goto fail;
            }
        }
    }
    double gx = c->gx - s[0], gy = c->gy - s[1];
    double along = -sin(s[2]) * gx + cos(s[2]) * gy;
    double sign = c->sense ? (double)c->sense : (along >= 0 ? 1.0 : -1.0);
    double limit;
    if (translation_limit(c, s, sign, &limit)) goto fail;
    if (limit >= c->b3 - c->eps) {
        PyObject *child = translate(c, s, sign * c->b3);
        if (!child) goto fail;
        if (child == Py_None) Py_DECREF(child);
        else if (append_move(out, 2, child)) goto fail;
    }
    double want = sign * along;
    want = want > 0.0 ? want : 0.0; /* max(0.0, sign * along) */
    double reach = want < limit ? want : limit; /* min(limit, ...) */
    if (reach > c->min_move) {
        PyObject *child = translate(c, s, sign * reach);
        if (!child) goto fail;
        if (child == Py_None) Py_DECREF(child);
        else if (append_move(out, 3, child)) goto fail;
    }
    return out;
fail:
    Py_DECREF(out);
    return NULL;
}

/* ---- leg moves (WalkProblem.leg_options) ------------------------------------------------- */

/* a - b of two integral doubles as a Python int, exactly (Python's ints) */
static PyObject *int_difference(double a, double b) {
    if (fabs(a) < 4503599627370496.0 && fabs(b) < 4503599627370496.0) /* 2^52: exact */
        return PyLong_FromDouble(a - b);
    PyObject *x = PyLong_FromDouble(a), *y = PyLong_FromDouble(b), *r = NULL;
    if (x && y) r = PyNumber_Subtract(x, y);
    Py_XDECREF(x);
    Py_XDECREF(y);
    return r;
}

/* (fx_idx - px_idx) << 40 j + (fy_idx - py_idx) << 40 (j + 1) as a Python int */
static PyObject *key_change(WalkCore *c, int j, double fix, double pix, double fiy,
                            double piy) {
    PyObject *a = int_difference(fix, pix), *b = int_difference(fiy, piy);
    PyObject *sa = NULL, *sb = NULL, *r = NULL;
    if (a && b) sa = PyNumber_Lshift(a, c->shift[j]);
    if (sa) sb = PyNumber_Lshift(b, c->shift[j + 1]);
    if (sb) r = PyNumber_Add(sa, sb);
    Py_XDECREF(a); Py_XDECREF(b); Py_XDECREF(sa); Py_XDECREF(sb);
    return r;
}

static int same_place(double fx, double fy, double px, double py) {
    return -1e-7 < fx - px && fx - px < 1e-7 && -1e-7 < fy - py && fy - py < 1e-7;
}

static int add_move(WalkCore *c, PyObject *part, long rule, int j, double fx, double fy,
                    double px, double py, const double s[11], int filter, double cs,
                    double sn) {
    if (same_place(fx, fy, px, py)) return 0;
    if (filter && !foot_ok(c, s[0] + cs * fx - sn * fy, s[1] + sn * fx + cs * fy)) return 0;
    PyObject *dk = key_change(c, j, nearbyint(fx * c->q), nearbyint(px * c->q),
                              nearbyint(fy * c->q), nearbyint(py * c->q));
    if (!dk) return -1;
    PyObject *m = Py_BuildValue("(lddN)", rule, fx, fy, dk);
    if (!m) return -1;
    int rc = PyList_Append(part, m);
    Py_DECREF(m);
    return rc;
}

static PyObject *WalkCore_leg_options(WalkCore *c, PyObject *state) {
    double s[11];
    int lift[4];
    if (!ready(c) || read_state(state, s) || liftable(c, s, lift)) return NULL;
    PyObject *out = PyList_New(0);
    if (!out) return NULL;
    if (!(lift[0] || lift[1] || lift[2] || lift[3])) return out;
    int filter = 0;
    if (c->terrain) {
        Py_ssize_t k; /* Terrain.feet_open */
        filter = !(grid_index(c, s[0], s[1], &k) && c->foot[k] >= c->r_robot + c->foot_thr);
    }
    double cs = filter ? cos(s[2]) : 0.0, sn = filter ? sin(s[2]) : 0.0;
    for (int leg = 0; leg < 4; leg++) {
        if (!lift[leg]) continue;
        int j = 3 + 2 * leg;
        double px = s[j], py = s[j + 1];
        PyObject *parts[3] = {PyList_New(0), PyList_New(0), PyList_New(0)};
        if (!parts[0] || !parts[1] || !parts[2]) goto fail_parts;
        for (int p = 0; p < 2; p++)
            if (add_move(c, parts[p], (p ? 8 : 4) + leg, j, c->fixed[leg][p][0],
                         c->fixed[leg][p][1], px, py, s, filter, cs, sn))
                goto fail_parts;
        if (c->set_b) {
            double hx = c->hx[leg], hy = c->hy[leg], rx = px - hx, ry = py - hy, length;
            if (py_hypot(c, rx, ry, &length)) goto fail_parts;
            if (length == 0.0) {
                PyErr_SetString(PyExc_ZeroDivisionError, "float division by zero");
                goto fail_parts;
            }
            double ux = rx / length, uy = ry / length;
            double t[4][3] = {
                {12 + leg, hx + c->lmax * ux, hy + c->lmax * uy},
                {16 + leg, hx + c->lmin * ux, hy + c->lmin * uy},
                {20 + leg, hx + length * c->unit_max[leg][0], hy + length * c->unit_max[leg][1]},
                {24 + leg, hx + length * c->unit_min[leg][0], hy + length * c->unit_min[leg][1]}};
            for (int m = 0; m < 4; m++)
                if (add_move(c, parts[2], (long)t[m][0], j, t[m][1], t[m][2], px, py, s,
                             filter, cs, sn))
                    goto fail_parts;
        }
        PyObject *item = Py_BuildValue("(i(NNN))", leg, parts[0], parts[1], parts[2]);
        if (!item) goto fail;
        if (PyList_Append(out, item)) { Py_DECREF(item); goto fail; }
        Py_DECREF(item);
        continue;
    fail_parts:
        Py_XDECREF(parts[0]); Py_XDECREF(parts[1]); Py_XDECREF(parts[2]);
        goto fail;
    }
    return out;
fail:
    Py_DECREF(out);
    return NULL;
}

/* ---- construction ------------------------------------------------------------------------- */

static int get_doubles(PyObject *seq, double *out, Py_ssize_t n, const char *what) {
    PyObject *f = PySequence_Fast(seq, what);
    if (!f) return -1;
    if (PySequence_Fast_GET_SIZE(f) != n) {
        PyErr_Format(PyExc_ValueError, "%s: expected %zd numbers", what, n);
        Py_DECREF(f);
        return -1;
    }
    for (Py_ssize_t i = 0; i < n; i++) {
        out[i] = PyFloat_AsDouble(PySequence_Fast_GET_ITEM(f, i));
        if (out[i] == -1.0 && PyErr_Occurred()) { Py_DECREF(f); return -1; }
    }
    Py_DECREF(f);
    return 0;
}

/* the float64 data of ``arr`` (n values); its buffer view is kept until dealloc */
static const double *grid_data(WalkCore *c, PyObject *arr, Py_ssize_t n) {
    Py_buffer *view = &c->views[c->nviews];
    if (PyObject_GetBuffer(arr, view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT)) return NULL;
    if (!(view->itemsize == 8 && view->format && strcmp(view->format, "d") == 0
          && view->len / 8 == n && view->len % 8 == 0)) {
        PyBuffer_Release(view);
        PyErr_SetString(PyExc_ValueError, "terrain arrays: expected C-contiguous float64 of "
                        "the grid's size");
        return NULL;
    }
    c->nviews++;
    return (const double *)view->buf;
}

/* WalkCore(model_numbers, problem_numbers, fixed_targets, units, terrain, key_offset)
 *  model_numbers: 4 x (hx, hy, side) then 4 x (h, th, out_c, in_c, c0, nh0, c1, nh1), then
 *                 cot, l_max, l_min, b/3, EPS, WORKSPACE_TOL, MIN_MOVE, stable, l_max ** 2
 *                 (53 numbers)
 *  problem_numbers: gx, gy, q, angle_grid, sense, set_b  (6)
 *  fixed_targets: 4 legs x 2 rules x (fx, fy)  (16); units: unit_max, unit_min (16)
 *  terrain: None or (terrain, body_sdf, foot_sdf, x0, y0, inv, nx, ny, r_hip, body_thr,
 *           foot_thr, r_robot, outline [k, 2], k, a / 2, b / 2, SPACING, QUICK_STEP) */
static int WalkCore_init(WalkCore *c, PyObject *args, PyObject *kw) {
    (void)kw;
    if (c->tried) { /* half-set fields of a failed or earlier call are never reused */
        PyErr_SetString(PyExc_RuntimeError, "WalkCore is initialised once");
        return -1;
    }
    c->tried = 1;
    PyObject *model, *problem, *fixed, *units, *terrain, *offset;
    if (!PyArg_ParseTuple(args, "OOOOOO", &model, &problem, &fixed, &units, &terrain, &offset))
        return -1;
    double m[53], p[6], f[16], u[16];
    if (get_doubles(model, m, 53, "model") || get_doubles(problem, p, 6, "problem")
        || get_doubles(fixed, f, 16, "fixed") || get_doubles(units, u, 16, "units"))
        return -1;
    for (int i = 0; i < 4; i++) {
        c->hx[i] = m[3 * i]; c->hy[i] = m[3 * i + 1]; c->side[i] = m[3 * i + 2];
        const double *r = m + 12 + 8 * i;
        c->rot_h[i] = r[0]; c->rot_th[i] = r[1]; c->rot_out[i] = r[2]; c->rot_in[i] = r[3];
        c->wedge_c[i][0] = r[4]; c->wedge_nh[i][0] = r[5];
        c->wedge_c[i][1] = r[6]; c->wedge_nh[i][1] = r[7];
        for (int k = 0; k < 2; k++) {
            c->fixed[i][k][0] = f[4 * i + 2 * k]; c->fixed[i][k][1] = f[4 * i + 2 * k + 1];
        }
        c->unit_max[i][0] = u[2 * i]; c->unit_max[i][1] = u[2 * i + 1];
        c->unit_min[i][0] = u[8 + 2 * i]; c->unit_min[i][1] = u[8 + 2 * i + 1];
    }
    c->cot = m[44]; c->lmax = m[45]; c->lmin = m[46]; c->b3 = m[47]; c->eps = m[48];
    c->workspace_tol = m[49]; c->min_move = m[50]; c->stable = m[51]; c->lmax2 = m[52];
    c->gx = p[0]; c->gy = p[1]; c->q = p[2]; c->angle_grid = p[3];
    c->sense = (int)p[4]; c->set_b = p[5] != 0.0;
    PyObject *math = PyImport_ImportModule("math");
    if (!math) return -1;
    Py_XSETREF(c->hypot, PyObject_GetAttrString(math, "hypot"));
    Py_DECREF(math);
    if (!c->hypot) return -1;
    Py_INCREF(offset);
    Py_XSETREF(c->key_offset, offset);
    for (int i = 0; i < KEY_FIELDS; i++) {
        Py_XSETREF(c->shift[i], PyLong_FromLong((long)KEY_BITS * i));
        if (!c->shift[i]) return -1;
    }
    if (terrain != Py_None) {
        PyObject *t, *body, *foot, *outline;
        double x0, y0, inv, r_hip, body_thr, foot_thr, r_robot, half_a, half_b, spacing, quick;
        Py_ssize_t nx, ny, n_outline;
        if (!PyArg_ParseTuple(terrain, "OOOdddnnddddOndddd", &t, &body, &foot, &x0, &y0, &inv,
                              &nx, &ny, &r_hip, &body_thr, &foot_thr, &r_robot, &outline,
                              &n_outline, &half_a, &half_b, &spacing, &quick))
            return -1;
        if (nx < 1 || ny < 1 || nx > PY_SSIZE_T_MAX / 8 / ny || n_outline < 0
            || n_outline > PY_SSIZE_T_MAX / 16) {
            PyErr_SetString(PyExc_ValueError, "terrain: bad grid or outline size");
            return -1;
        }
        if (!(isfinite(spacing) && spacing > 0 && isfinite(quick) && quick > 0
              && isfinite(inv) && inv > 0)) {
            PyErr_SetString(PyExc_ValueError, "terrain: expected spacings > 0");
            return -1;
        }
        c->body = grid_data(c, body, nx * ny);
        if (!c->body) return -1;
        c->foot = grid_data(c, foot, nx * ny);
        if (!c->foot) return -1;
        c->outline = grid_data(c, outline, 2 * n_outline);
        if (!c->outline) return -1;
        c->n_outline = n_outline; c->half_a = half_a; c->half_b = half_b;
        c->spacing = spacing; c->quick = quick;
        Py_INCREF(t);
        Py_XSETREF(c->terrain, t);
        c->tx0 = x0; c->ty0 = y0; c->inv = inv; c->nx = nx; c->ny = ny;
        c->r_hip = r_hip; c->body_thr = body_thr; c->foot_thr = foot_thr; c->r_robot = r_robot;
    }
    c->initialised = 1;
    return 0;
}

static void WalkCore_dealloc(WalkCore *c) {
    for (int i = 0; i < c->nviews; i++) PyBuffer_Release(&c->views[i]);
    Py_XDECREF(c->terrain);
    Py_XDECREF(c->hypot); Py_XDECREF(c->key_offset);
    for (int i = 0; i < KEY_FIELDS; i++) Py_XDECREF(c->shift[i]);
    Py_TYPE(c)->tp_free((PyObject *)c);
}

static PyMethodDef WalkCore_methods[] = {
    {"body_moves", (PyCFunction)WalkCore_body_moves, METH_O,
     "WalkProblem.body_moves(state): rules 1-3 as (rule, child, 1.0)."},
    {"leg_options", (PyCFunction)WalkCore_leg_options, METH_O,
     "WalkProblem.leg_options(state): (leg, (rules 4+leg, 8+leg, 12-27)) per liftable leg."},
    {NULL, NULL, 0, NULL}};

static PyTypeObject WalkCoreType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "evomotion.studies.quadruped_plan.rules._walkcore.WalkCore",
    .tp_basicsize = sizeof(WalkCore),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "The compiled successors of one WalkProblem (see the module doc).",
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)WalkCore_init,
    .tp_dealloc = (destructor)WalkCore_dealloc,
    .tp_methods = WalkCore_methods,
};

static struct PyModuleDef walkcore_module = {
    PyModuleDef_HEAD_INIT,
    .m_name = "_walkcore",
    .m_doc = "Compiled successor generation of the quadruped walking problem (_walkcore.c).",
    .m_size = -1,
};

PyMODINIT_FUNC PyInit__walkcore(void) {
    if (PyType_Ready(&WalkCoreType) < 0) return NULL;
    PyObject *m = PyModule_Create(&walkcore_module);
    if (!m) return NULL;
    Py_INCREF(&WalkCoreType);
    if (PyModule_AddObject(m, "WalkCore", (PyObject *)&WalkCoreType) < 0) {
        Py_DECREF(&WalkCoreType);
        Py_DECREF(m);
        return NULL;
    }
    return m;
}

/*
 * benches/embree/harness.c: the Embree side of rayreel's side-by-side mesh comparison
 * (issue 26, "Targets").
 *
 * Loads a triangle mesh (PLY or OBJ), builds an Embree 3 scene, times the build, then renders
 * frames of eye rays (one per pixel, through the pixel centre) and, for every hit, one shadow
 * ray to a point light, with rtcIntersect16 / rtcOccluded16 on 4x4 pixel tiles, spread over
 * pthreads. Prints one JSON line on stdout. See README.md beside this file.
 *
 * Build: benches/embree/build.sh   (gcc -O3 -march=native ... -lembree3 -lm -lpthread)
 *
 * ---------------------------------------------------------------------------------------
 * Camera: exactly rayreel's (README.md, "The tracer" and "The arithmetic, exactly"):
 *
 *   "Pixel (row i from the top, column j from the left) of a W×H image samples its centre:
 *    screen point x = −1 + 2(j+0.5)/W, y = (1 − 2(i+0.5)/H)·H/W, direction
 *    normalize(forward + x·tan(fov/2)·right + y·tan(fov/2)·up)."
 *   "Camera. forward = (look_at − position)/|look_at − position| (per component division);
 *    up′ = up − (up·forward)·forward; up_c = normalize(up′); right = forward × up_c;
 *    s = libm tan((fov·(π/180))·0.5)."
 *   "Eye ray of sample offset (u, v) ∈ [0,1)² in pixel (i, j): x = −1 + (2(j + u))/W,
 *    y = ((1 − (2(i + v))/H)·H)/W; d = normalize((forward + (x·s)·right) + (y·s)·up_c);
 *    origin = the camera position."
 *   "camera.fov | 90 | degrees, (0, 180) | horizontal field of view"
 *   Vectors: "a·b = (aₓbₓ + a_yb_y) + a_zb_z, left to right; |v| = √(v·v); normalize(v) =
 *    v·r per component with r = 1/|v|; a×b = (a_yb_z − b_ya_z, a_zbₓ − b_za_x, aₓb_y − bₓa_y)".
 *
 * So: the fov is HORIZONTAL (x spans [−1, 1] across the image width, y spans ±H/W), rows are
 * counted from the top (image y down, screen y up), one sample at the pixel centre (u = v = ½),
 * right = forward × up_c (with forward −z and up +y, right is +x: a right-handed world seen
 * by a camera looking down −z). The basis and s are computed in double in exactly that order
 * (glibc tan() standing in for libm's). Then, as rayreel's two precisions do:
 *   --rays f32 (default; rayreel's "f32, exactly"): camera-relative: the mesh's vertices and
 *     the light have the camera position o subtracted in double, then are rounded to float;
 *     the eye rays leave from 0; forward, right, up_c, s, the pixel's row and column and the
 *     literals are rounded to float and x, y, the sum and normalize are float operations in
 *     the order above (built with -ffp-contract=off, so no fused multiply-adds).
 *   --rays f64 (rayreel's f64 rule): d computed in double, then rounded to float; the origin
 *     is (float)o and the mesh stays in world coordinates, rounded to float.
 * Embree itself intersects in float either way.
 *
 * Shadow rays (float): P = org + t·d, Ng = Embree's geometric normal,
 * normalised and turned toward the light; origin = P + Ng·eps·scale with
 * eps = 2^-17 (≈ 7.6e-6, i.e. 64 float ulps) and scale = max(|P|∞, |org|∞, t), direction = the
 * unit vector to the light, tnear = 0, tfar = the distance from that origin to the light.
 * With --shadow all (default) every eye hit casts one; with --shadow facing only hits whose
 * eye-facing geometric normal has N·L > 0 do (rayreel's rule "nothing more unless ¬(n_l ≤ 0)"
 * with the flat normal); the rest are counted as "backlit". --shadow none: eye rays only.
 *
 * Instanced modes (off by default; without them every other mode is unchanged):
 *   --grid N [--grid-scale S]: the mesh is built once as its own scene (the BLAS), and a top
 *     scene holds N·N RTC_GEOMETRY_TYPE_INSTANCE geometries of it; instance i (its geometry ID)
 *     is scale S (0.35), then R_y((i·37) mod 360 degrees) = [[c,0,s],[0,1,0],[−s,0,c]], then
 *     translate (i mod N + 0.5, 0, i div N + 0.5).
 *   --single-scale S [--single-at x,y,z]: one instance, scale S, no rotation, at x,y,z (0,0,0).
 *   The rays are world-space there in both --rays modes (no camera-relative shift; --rays picks
 *   only the eye directions' arithmetic), and Embree's Ng, which is in the instanced scene's
 *   space, is turned to world space with the instance's rotation before the shadow set-up.
 * ---------------------------------------------------------------------------------------
 */
#define _GNU_SOURCE
#include <embree3/rtcore.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>

/* ------------------------------------------------------------------------------------ */
/* small helpers                                                                         */

static void die(const char* fmt, ...) __attribute__((noreturn, format(printf, 1, 2)));
static void die(const char* fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    fputs("harness: error: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    exit(2);
}

static double now_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* CPU time of the whole process (all threads, Embree's TBB workers included) */
static double cpu_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static void* xmalloc(size_t n) {
    void* p = malloc(n ? n : 1);
    if (!p) die("out of memory (%zu bytes)", n);
    return p;
}

static int cmp_double(const void* a, const void* b) {
    double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

static double median(double* v, int n) {
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return (n % 2) ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* ------------------------------------------------------------------------------------ */
/* mesh                                                                                  */

typedef struct {
    double* pos;    /* 3 per vertex, as read (rounded to float for Embree, see main) */
    size_t nv, cap_v;
    uint32_t* tri;  /* 3 per triangle */
    size_t nt, cap_t;
    size_t polygons; /* faces in the file */
} Mesh;

static void mesh_add_vertex(Mesh* m, double x, double y, double z) {
    if (m->nv == m->cap_v) {
        m->cap_v = m->cap_v ? m->cap_v * 2 : 1024;
        m->pos = realloc(m->pos, m->cap_v * 3 * sizeof(double));
        if (!m->pos) die("out of memory");
    }
    m->pos[3 * m->nv + 0] = x;
    m->pos[3 * m->nv + 1] = y;
    m->pos[3 * m->nv + 2] = z;
    m->nv++;
}

static void mesh_add_tri(Mesh* m, uint32_t a, uint32_t b, uint32_t c) {
    if (m->nt == m->cap_t) {
        m->cap_t = m->cap_t ? m->cap_t * 2 : 1024;
        m->tri = realloc(m->tri, m->cap_t * 3 * sizeof(uint32_t));
        if (!m->tri) die("out of memory");
    }
    m->tri[3 * m->nt + 0] = a;
    m->tri[3 * m->nt + 1] = b;
    m->tri[3 * m->nt + 2] = c;
    m->nt++;
}

/* Fan a polygon v0 v1 ... v(n-1) into (v0, vk, vk+1). */
static void mesh_add_polygon(Mesh* m, const uint32_t* idx, size_t n) {
    m->polygons++;
    for (size_t k = 1; k + 1 < n; k++) mesh_add_tri(m, idx[0], idx[k], idx[k + 1]);
}

static char* read_file(const char* path, size_t* len) {
    FILE* f = fopen(path, "rb");
    if (!f) die("%s: %s", path, strerror(errno));
    size_t cap = 1 << 20, n = 0;
    char* buf = xmalloc(cap + 1);
    for (;;) {
        if (n == cap) {
            cap *= 2;
            buf = realloc(buf, cap + 1);
            if (!buf) die("out of memory reading %s", path);
        }
        size_t got = fread(buf + n, 1, cap - n, f);
        n += got;
        if (got == 0) {
            if (ferror(f)) die("%s: read error", path);
            break;
        }
    }
    fclose(f);
    buf[n] = 0;
    *len = n;
    return buf;
}

/* ---- PLY: ascii, binary_little_endian, binary_big_endian ---------------------------- */

typedef enum { T_NONE, T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_F32, T_F64 } PlyType;

static PlyType ply_type(const char* s) {
    static const struct { const char* n; PlyType t; } tab[] = {
        {"char", T_I8},    {"int8", T_I8},     {"uchar", T_U8},   {"uint8", T_U8},
        {"short", T_I16},  {"int16", T_I16},   {"ushort", T_U16}, {"uint16", T_U16},
        {"int", T_I32},    {"int32", T_I32},   {"uint", T_U32},   {"uint32", T_U32},
        {"float", T_F32},  {"float32", T_F32}, {"double", T_F64}, {"float64", T_F64},
    };
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
        if (!strcmp(s, tab[i].n)) return tab[i].t;
    return T_NONE;
}

static size_t ply_size(PlyType t) {
    switch (t) {
        case T_I8: case T_U8: return 1;
        case T_I16: case T_U16: return 2;
        case T_I32: case T_U32: case T_F32: return 4;
        case T_F64: return 8;
        default: return 0;
    }
}

typedef struct {
    char name[64];
    bool is_list;
    PlyType count_type, type;
} PlyProp;

typedef struct {
    char name[64];
    size_t count;
    PlyProp props[32];
    int nprops;
} PlyElem;

enum { FMT_ASCII, FMT_LE, FMT_BE };

typedef struct {
    const char* p;
    const char* end;
    int fmt;
    const char* path;
} PlyReader;

static double ply_read(PlyReader* r, PlyType t, const char* what, size_t index) {
    if (r->fmt == FMT_ASCII) {
        while (r->p < r->end && (*r->p == ' ' || *r->p == '\t' || *r->p == '\r' || *r->p == '\n'))
            r->p++;
        if (r->p >= r->end) die("%s: truncated in %s %zu", r->path, what, index);
        char* e;
        double v = strtod(r->p, &e);
        if (e == r->p) die("%s: bad number in %s %zu", r->path, what, index);
        r->p = e;
        return v;
    }
    size_t n = ply_size(t);
    if ((size_t)(r->end - r->p) < n) die("%s: truncated in %s %zu", r->path, what, index);
    unsigned char b[8];
    memcpy(b, r->p, n);
    r->p += n;
    if (r->fmt == FMT_BE)
        for (size_t i = 0; i < n / 2; i++) { unsigned char c = b[i]; b[i] = b[n - 1 - i]; b[n - 1 - i] = c; }
    switch (t) {
        case T_I8: return (int8_t)b[0];
        case T_U8: return b[0];
        case T_I16: { int16_t v; memcpy(&v, b, 2); return v; }
        case T_U16: { uint16_t v; memcpy(&v, b, 2); return v; }
        case T_I32: { int32_t v; memcpy(&v, b, 4); return v; }
        case T_U32: { uint32_t v; memcpy(&v, b, 4); return v; }
        case T_F32: { float v; memcpy(&v, b, 4); return v; }
        case T_F64: { double v; memcpy(&v, b, 8); return v; }
        default: return 0;
    }
}

static void load_ply(const char* path, Mesh* m) {
    size_t len;
    char* buf = read_file(path, &len);
    if (len < 4 || memcmp(buf, "ply", 3) != 0) die("%s: not a PLY file", path);
    const char* hend = strstr(buf, "end_header");
    if (!hend) die("%s: PLY header has no end_header", path);
    const char* body = strchr(hend, '\n');
    if (!body) die("%s: truncated after end_header", path);
    body++;

    PlyElem elems[16];
    int nelems = 0, fmt = -1;
    /* parse header line by line */
    const char* line = buf;
    while (line < hend) {
        const char* nl = strchr(line, '\n');
        size_t ll = (size_t)(nl - line);
        char tmp[512];
        if (ll >= sizeof tmp) ll = sizeof tmp - 1;
        memcpy(tmp, line, ll);
        tmp[ll] = 0;
        if (ll && tmp[ll - 1] == '\r') tmp[ll - 1] = 0;
        line = nl + 1;
        char* tok[8];
        int nt = 0;
        for (char* s = strtok(tmp, " \t"); s && nt < 8; s = strtok(NULL, " \t")) tok[nt++] = s;
        if (nt == 0) continue;
        if (!strcmp(tok[0], "format") && nt >= 2) {
            if (!strcmp(tok[1], "ascii")) fmt = FMT_ASCII;
            else if (!strcmp(tok[1], "binary_little_endian")) fmt = FMT_LE;
            else if (!strcmp(tok[1], "binary_big_endian")) fmt = FMT_BE;
            else die("%s: unknown PLY format %s", path, tok[1]);
        } else if (!strcmp(tok[0], "element") && nt >= 3) {
            if (nelems == 16) die("%s: too many PLY elements", path);
            PlyElem* e = &elems[nelems++];
            memset(e, 0, sizeof *e);
            snprintf(e->name, sizeof e->name, "%s", tok[1]);
            e->count = strtoull(tok[2], NULL, 10);
        } else if (!strcmp(tok[0], "property") && nt >= 3) {
            if (nelems == 0) die("%s: PLY property before any element", path);
            PlyElem* e = &elems[nelems - 1];
            if (e->nprops == 32) die("%s: too many PLY properties", path);
            PlyProp* p = &e->props[e->nprops++];
            memset(p, 0, sizeof *p);
            if (!strcmp(tok[1], "list")) {
                if (nt < 5) die("%s: bad PLY list property", path);
                p->is_list = true;
                p->count_type = ply_type(tok[2]);
                p->type = ply_type(tok[3]);
                snprintf(p->name, sizeof p->name, "%s", tok[4]);
                if (!p->count_type || !p->type) die("%s: unknown PLY type in list %s", path, tok[4]);
            } else {
                p->type = ply_type(tok[1]);
                snprintf(p->name, sizeof p->name, "%s", tok[2]);
                if (!p->type) die("%s: unknown PLY type %s", path, tok[1]);
            }
        }
    }
    if (fmt < 0) die("%s: PLY header has no format line", path);

    PlyReader r = {body, buf + len, fmt, path};
    bool have_faces = false;
    size_t vertex_count = 0;
    uint32_t* poly = xmalloc(256 * sizeof(uint32_t));
    for (int ei = 0; ei < nelems; ei++) {
        PlyElem* e = &elems[ei];
        bool is_vertex = !strcmp(e->name, "vertex");
        bool is_face = !strcmp(e->name, "face");
        int ix = -1, iy = -1, iz = -1, iidx = -1;
        for (int k = 0; k < e->nprops; k++) {
            if (is_vertex && !e->props[k].is_list) {
                if (!strcmp(e->props[k].name, "x")) ix = k;
                if (!strcmp(e->props[k].name, "y")) iy = k;
                if (!strcmp(e->props[k].name, "z")) iz = k;
            }
            if (is_face && e->props[k].is_list &&
                (!strcmp(e->props[k].name, "vertex_indices") || !strcmp(e->props[k].name, "vertex_index")))
                iidx = k;
        }
        if (is_vertex && (ix < 0 || iy < 0 || iz < 0)) die("%s: PLY vertex has no x, y, z", path);
        if (is_face && iidx < 0) die("%s: PLY face has no vertex_indices list", path);
        if (is_vertex) vertex_count = e->count;
        if (is_face) have_faces = true;
        /* fast path: binary LE vertex with only float properties */
        bool fast_vertex = is_vertex && fmt == FMT_LE;
        for (int k = 0; k < e->nprops && fast_vertex; k++)
            if (e->props[k].is_list || e->props[k].type != T_F32) fast_vertex = false;
        if (fast_vertex) {
            size_t stride = 4 * (size_t)e->nprops;
            if ((size_t)(r.end - r.p) / stride < e->count) die("%s: truncated in vertex data", path);
            for (size_t i = 0; i < e->count; i++) {
                float f[32];
                memcpy(f, r.p + i * stride, stride);
                mesh_add_vertex(m, f[ix], f[iy], f[iz]);
            }
            r.p += e->count * stride;
            continue;
        }
        for (size_t i = 0; i < e->count; i++) {
            double xyz[3] = {0, 0, 0};
            for (int k = 0; k < e->nprops; k++) {
                PlyProp* p = &e->props[k];
                if (p->is_list) {
                    double c = ply_read(&r, p->count_type, e->name, i);
                    if (!(c >= 0 && c <= 255 && c == floor(c)))
                        die("%s: %s %zu: bad list length %g", path, e->name, i, c);
                    size_t n = (size_t)c;
                    for (size_t q = 0; q < n; q++) {
                        double v = ply_read(&r, p->type, e->name, i);
                        if (k == iidx) {
                            if (!(v >= 0 && v < (double)vertex_count && v == floor(v)))
                                die("%s: face %zu: vertex index %g out of range (%zu vertices)", path, i, v,
                                    vertex_count);
                            poly[q] = (uint32_t)v;
                        }
                    }
                    if (k == iidx) {
                        if (n < 3) die("%s: face %zu has %zu vertices (fewer than 3)", path, i, n);
                        mesh_add_polygon(m, poly, n);
                    }
                } else {
                    double v = ply_read(&r, p->type, e->name, i);
                    if (k == ix) xyz[0] = v;
                    if (k == iy) xyz[1] = v;
                    if (k == iz) xyz[2] = v;
                }
            }
            if (is_vertex) mesh_add_vertex(m, xyz[0], xyz[1], xyz[2]);
        }
    }
    free(poly);
    free(buf);
    if (!have_faces) die("%s: PLY has no face element", path);
}

/* ---- OBJ: v and f (v, v/t, v//n, v/t/n; negative indices), polygons fanned ------------- */

static void load_obj(const char* path, Mesh* m) {
    size_t len;
    char* buf = read_file(path, &len);
    size_t cap = 64;
    uint32_t* poly = xmalloc(cap * sizeof(uint32_t));
    size_t lineno = 0;
    char* p = buf;
    while (*p) {
        lineno++;
        char* eol = strchr(p, '\n');
        if (eol) *eol = 0;
        while (*p == ' ' || *p == '\t') p++;
        if (p[0] == 'v' && (p[1] == ' ' || p[1] == '\t')) {
            char* e;
            double x = strtod(p + 1, &e);
            double y = strtod(e, &e);
            double z = strtod(e, &e);
            mesh_add_vertex(m, x, y, z);
        } else if (p[0] == 'f' && (p[1] == ' ' || p[1] == '\t')) {
            size_t n = 0;
            char* s = p + 1;
            for (;;) {
                while (*s == ' ' || *s == '\t' || *s == '\r') s++;
                if (!*s) break;
                char* e;
                long v = strtol(s, &e, 10);
                if (e == s) die("%s:%zu: bad face index", path, lineno);
                long idx = v > 0 ? v - 1 : (long)m->nv + v;
                if (v == 0 || idx < 0 || (size_t)idx >= m->nv)
                    die("%s:%zu: vertex index %ld out of range (%zu vertices so far)", path, lineno, v, m->nv);
                if (n == cap) {
                    cap *= 2;
                    poly = realloc(poly, cap * sizeof(uint32_t));
                    if (!poly) die("out of memory");
                }
                poly[n++] = (uint32_t)idx;
                s = e;
                while (*s && *s != ' ' && *s != '\t' && *s != '\r') s++; /* skip /t/n */
            }
            if (n < 3) die("%s:%zu: face with fewer than 3 vertices", path, lineno);
            mesh_add_polygon(m, poly, n);
        }
        if (!eol) break;
        p = eol + 1;
    }
    free(poly);
    free(buf);
}

/* ------------------------------------------------------------------------------------ */
/* options                                                                               */

typedef struct {
    const char* mesh;
    int width, height, threads, repeat, build_repeat;
    double eye[3], look_at[3], up[3], fov, light[3];
    const char* depth_out;
    const char* primid_out;
    bool depth_planar;
    bool shadow_facing, shadow_none;
    bool rays_f64;
    enum RTCBuildQuality quality;
    bool robust;
    int grid;            /* --grid N: N*N instances of the mesh (0: off, the plain one-mesh scene) */
    double grid_scale;   /* --grid-scale S: their uniform scale (0.35) */
    double single_scale; /* --single-scale S: one instance, scale S, at --single-at (0: off) */
    double single_at[3]; /* --single-at x,y,z (0,0,0) */
} Options;

/* A fresh scene with the build quality and flags the options ask for. */
static RTCScene new_scene(RTCDevice dev, const Options* o) {
    RTCScene s = rtcNewScene(dev);
    rtcSetSceneBuildQuality(s, o->quality);
    rtcSetSceneFlags(s, o->robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    return s;
}

/* Builds `s`'s hierarchy, writing the wall and CPU milliseconds the commit took. */
static void commit_timed(RTCScene s, double* wall, double* cpu) {
    double t = now_ms(), c = cpu_ms();
    rtcCommitScene(s);
    *wall = now_ms() - t;
    *cpu = cpu_ms() - c;
}

static void parse_vec(const char* s, double v[3], const char* name) {
    char* e;
    for (int k = 0; k < 3; k++) {
        v[k] = strtod(s, &e);
        if (e == s) die("%s wants x,y,z, got '%s'", name, s);
        s = e;
        if (k < 2) {
            if (*s != ',') die("%s wants x,y,z", name);
            s++;
        }
    }
    if (*s) die("%s wants x,y,z", name);
}

static long parse_int(const char* s, const char* name, long lo, long hi) {
    char* e;
    long v = strtol(s, &e, 10);
    if (e == s || *e || v < lo || v > hi) die("%s wants a whole number in [%ld, %ld], got '%s'", name, lo, hi, s);
    return v;
}

static void usage(void) {
    fputs("usage: harness MESH.ply|MESH.obj --width W --height H --eye x,y,z --look-at x,y,z\n"
          "               --up x,y,z --fov DEG --light x,y,z [--threads 2] [--repeat N]\n"
          "               [--build-repeat N] [--quality low|medium|high] [--robust]\n"
          "               [--rays f32|f64] [--shadow all|facing|none]\n"
          "               [--depth-out FILE.pfm] [--depth-kind ray|planar]\n"
          "               [--primid-out FILE.u32]\n"
          "               [--grid N [--grid-scale S]] | [--single-scale S [--single-at x,y,z]]\n",
          stderr);
    exit(2);
}

static Options parse_args(int argc, char** argv) {
    Options o;
    memset(&o, 0, sizeof o);
    o.width = 1920; o.height = 1080; o.threads = 2; o.repeat = 10; o.build_repeat = 3;
    o.up[1] = 1; o.fov = 90; o.quality = RTC_BUILD_QUALITY_MEDIUM;
    o.grid_scale = 0.35;
    bool have_eye = false, have_at = false, have_light = false;
    for (int i = 1; i < argc; i++) {
        const char* a = argv[i];
        if (a[0] != '-' || a[1] != '-') {
            if (o.mesh) die("more than one mesh given ('%s' and '%s')", o.mesh, a);
            o.mesh = a;
            continue;
        }
        if (!strcmp(a, "--robust")) { o.robust = true; continue; }
        if (!strcmp(a, "--help")) usage();
        if (i + 1 >= argc) die("%s wants a value", a);
        const char* v = argv[++i];
        if (!strcmp(a, "--width")) o.width = (int)parse_int(v, a, 1, 1 << 16);
        else if (!strcmp(a, "--height")) o.height = (int)parse_int(v, a, 1, 1 << 16);
        else if (!strcmp(a, "--threads")) o.threads = (int)parse_int(v, a, 1, 256);
        else if (!strcmp(a, "--repeat")) o.repeat = (int)parse_int(v, a, 1, 100000);
        else if (!strcmp(a, "--build-repeat")) o.build_repeat = (int)parse_int(v, a, 1, 1000);
        else if (!strcmp(a, "--eye")) { parse_vec(v, o.eye, a); have_eye = true; }
        else if (!strcmp(a, "--look-at")) { parse_vec(v, o.look_at, a); have_at = true; }
        else if (!strcmp(a, "--up")) parse_vec(v, o.up, a);
        else if (!strcmp(a, "--light")) { parse_vec(v, o.light, a); have_light = true; }
        else if (!strcmp(a, "--fov")) {
            char* e;
            o.fov = strtod(v, &e);
            if (e == v || *e || !(o.fov > 0 && o.fov < 180)) die("--fov wants degrees in (0, 180)");
        } else if (!strcmp(a, "--depth-out")) o.depth_out = v;
        else if (!strcmp(a, "--primid-out")) o.primid_out = v;
        else if (!strcmp(a, "--depth-kind")) {
            if (!strcmp(v, "ray")) o.depth_planar = false;
            else if (!strcmp(v, "planar")) o.depth_planar = true;
            else die("--depth-kind wants ray or planar");
        } else if (!strcmp(a, "--shadow")) {
            if (!strcmp(v, "all")) o.shadow_facing = false;
            else if (!strcmp(v, "facing")) o.shadow_facing = true;
            else if (!strcmp(v, "none")) o.shadow_none = true;
            else die("--shadow wants all, facing or none");
        } else if (!strcmp(a, "--rays")) {
            if (!strcmp(v, "f32")) o.rays_f64 = false;
            else if (!strcmp(v, "f64")) o.rays_f64 = true;
            else die("--rays wants f32 or f64");
        } else if (!strcmp(a, "--quality")) {
            if (!strcmp(v, "low")) o.quality = RTC_BUILD_QUALITY_LOW;
            else if (!strcmp(v, "medium")) o.quality = RTC_BUILD_QUALITY_MEDIUM;
            else if (!strcmp(v, "high")) o.quality = RTC_BUILD_QUALITY_HIGH;
            else die("--quality wants low, medium or high");
        } else if (!strcmp(a, "--grid")) o.grid = (int)parse_int(v, a, 0, 1000);
        else if (!strcmp(a, "--grid-scale") || !strcmp(a, "--single-scale")) {
            char* e;
            double x = strtod(v, &e);
            if (e == v || *e || !(x >= 0 && x < 1e30) || (!strcmp(a, "--grid-scale") && !(x > 0)))
                die("%s wants a positive number%s", a, strcmp(a, "--grid-scale") ? " (0: off)" : "");
            if (!strcmp(a, "--grid-scale")) o.grid_scale = x; else o.single_scale = x;
        } else if (!strcmp(a, "--single-at")) parse_vec(v, o.single_at, a);
        else die("unknown option %s", a);
    }
    if (!o.mesh) usage();
    if (!have_eye || !have_at || !have_light) die("--eye, --look-at and --light are required");
    if (o.grid > 0 && o.single_scale > 0) die("--grid and --single-scale exclude each other");
    return o;
}

/* ------------------------------------------------------------------------------------ */
/* camera (rayreel's, see the header comment)                                           */

static double dot3(const double a[3], const double b[3]) { return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]; }

typedef struct {
    bool f32;                 /* --rays f32: rayreel's f32 rule; else its f64 rule */
    double pos[3];            /* the camera position o (world) */
    double fwd[3], up[3], right[3], s; /* f64 basis and s = tan(fov/2) */
    float fwd_f[3], up_f[3], right_f[3]; /* the same rounded to f32 */
    double* xs_d; double* ys_d; /* per column x·s and per row y·s in f64 */
    float* xs_f; float* ys_f;   /* ... and with f32 arithmetic */
    float org[3];   /* the eye rays' origin handed to Embree: 0 (f32, camera-relative) or (float)o */
    float light[3]; /* the light, in the same frame as the mesh handed to Embree */
    float org_max;  /* max |org component| */
} Camera;

static Camera make_camera(const Options* o) {
    Camera c;
    memset(&c, 0, sizeof c);
    c.f32 = !o->rays_f64;
    double d[3];
    for (int k = 0; k < 3; k++) { c.pos[k] = o->eye[k]; d[k] = o->look_at[k] - o->eye[k]; }
    double len = sqrt(dot3(d, d));
    if (!(len > 0)) die("--look-at must differ from --eye");
    for (int k = 0; k < 3; k++) c.fwd[k] = d[k] / len;
    double uf = dot3(o->up, c.fwd), u[3];
    for (int k = 0; k < 3; k++) u[k] = o->up[k] - uf * c.fwd[k];
    double ul = sqrt(dot3(u, u));
    if (!(ul > 0)) die("--up is parallel to the view direction");
    double r = 1.0 / ul;
    for (int k = 0; k < 3; k++) c.up[k] = u[k] * r;
    const double* a = c.fwd; const double* b = c.up;
    c.right[0] = a[1] * b[2] - b[1] * a[2];
    c.right[1] = a[2] * b[0] - b[2] * a[0];
    c.right[2] = a[0] * b[1] - b[0] * a[1];
    c.s = tan((o->fov * (M_PI / 180.0)) * 0.5);
    for (int k = 0; k < 3; k++) {
        c.fwd_f[k] = (float)c.fwd[k]; c.up_f[k] = (float)c.up[k]; c.right_f[k] = (float)c.right[k];
    }
    /* x = −1 + (2(j + ½))/W, y = ((1 − (2(i + ½))/H)·H)/W, then x·s and y·s: per column and row */
    const int W = o->width, H = o->height;
    c.xs_d = xmalloc((size_t)W * sizeof(double)); c.xs_f = xmalloc((size_t)W * sizeof(float));
    c.ys_d = xmalloc((size_t)H * sizeof(double)); c.ys_f = xmalloc((size_t)H * sizeof(float));
    const float sf = (float)c.s, Wf = (float)W, Hf = (float)H;
    for (int j = 0; j < W; j++) {
        c.xs_d[j] = (-1.0 + (2.0 * (j + 0.5)) / W) * c.s;
        c.xs_f[j] = (-1.0f + (2.0f * ((float)j + 0.5f)) / Wf) * sf;
    }
    for (int i = 0; i < H; i++) {
        c.ys_d[i] = (((1.0 - (2.0 * (i + 0.5)) / H) * H) / W) * c.s;
        c.ys_f[i] = (((1.0f - (2.0f * ((float)i + 0.5f)) / Hf) * Hf) / Wf) * sf;
    }
    for (int k = 0; k < 3; k++) {
        c.org[k] = c.f32 ? 0.0f : (float)c.pos[k];
        c.light[k] = c.f32 ? (float)(o->light[k] - c.pos[k]) : (float)o->light[k];
    }
    c.org_max = fmaxf(fmaxf(fabsf(c.org[0]), fabsf(c.org[1])), fabsf(c.org[2]));
    return c;
}

/* ------------------------------------------------------------------------------------ */
/* rendering                                                                             */

#define SHADOW_EPS (1.0f / 131072.0f) /* 2^-17 */
#define MAXF(a, b) ((a) > (b) ? (a) : (b))

typedef struct {
    uint64_t hits, shadow_rays, shadowed, backlit;
} Stats;

typedef struct {
    const Options* o;
    const Camera* cam;
    RTCScene scene;
    int tiles_x, tiles_y;
    int next_row; /* atomic: next row of tiles to take */
    float* depth;
    uint32_t* primid;
    /* instanced modes (--grid, --single-scale): per instance (its geometry ID in the top scene)
     * cos and sin of its rotation about +y, to turn Embree's object-space Ng into world space;
     * NULL in the plain one-mesh mode */
    const float* inst_cos;
    const float* inst_sin;
    unsigned ninst;
} Frame;

typedef struct {
    Frame* f;
    Stats st;
} Worker;

static void render_tile(Frame* f, int tx, int ty, Stats* st) {
    const Options* o = f->o;
    const Camera* c = f->cam;
    const int W = o->width, H = o->height;
    struct RTCRayHit16 rh __attribute__((aligned(64)));
    struct RTCRay16 sr __attribute__((aligned(64)));
    int valid[16] __attribute__((aligned(64)));
    int svalid[16] __attribute__((aligned(64)));
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;

    /* eye rays: d = normalize((forward + (x·s)·right) + (y·s)·up_c), normalize(v) = v·(1/√(v·v)) */
    if (c->f32) {
#pragma omp simd
        for (int k = 0; k < 16; k++) {
            int i = ty * 4 + (k >> 2), j = tx * 4 + (k & 3);
            valid[k] = (i < H && j < W) ? -1 : 0;
            float xs = c->xs_f[j < W ? j : W - 1], ys = c->ys_f[i < H ? i : H - 1];
            float vx = (c->fwd_f[0] + xs * c->right_f[0]) + ys * c->up_f[0];
            float vy = (c->fwd_f[1] + xs * c->right_f[1]) + ys * c->up_f[1];
            float vz = (c->fwd_f[2] + xs * c->right_f[2]) + ys * c->up_f[2];
            float r = 1.0f / sqrtf((vx * vx + vy * vy) + vz * vz);
            rh.ray.dir_x[k] = vx * r; rh.ray.dir_y[k] = vy * r; rh.ray.dir_z[k] = vz * r;
        }
    } else {
        for (int k = 0; k < 16; k++) {
            int i = ty * 4 + (k >> 2), j = tx * 4 + (k & 3);
            valid[k] = (i < H && j < W) ? -1 : 0;
            double xs = c->xs_d[j < W ? j : W - 1], ys = c->ys_d[i < H ? i : H - 1];
            double vx = (c->fwd[0] + xs * c->right[0]) + ys * c->up[0];
            double vy = (c->fwd[1] + xs * c->right[1]) + ys * c->up[1];
            double vz = (c->fwd[2] + xs * c->right[2]) + ys * c->up[2];
            double r = 1.0 / sqrt((vx * vx + vy * vy) + vz * vz);
            rh.ray.dir_x[k] = (float)(vx * r); rh.ray.dir_y[k] = (float)(vy * r); rh.ray.dir_z[k] = (float)(vz * r);
        }
    }
    for (int k = 0; k < 16; k++) {
        rh.ray.org_x[k] = c->org[0]; rh.ray.org_y[k] = c->org[1]; rh.ray.org_z[k] = c->org[2];
        rh.ray.tnear[k] = 0.0f;
        rh.ray.tfar[k] = INFINITY;
        rh.ray.time[k] = 0.0f;
        rh.ray.mask[k] = 0xFFFFFFFFu;
        rh.ray.id[k] = (unsigned)k;
        rh.ray.flags[k] = 0;
        rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.primID[k] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect16(valid, f->scene, &ctx, &rh);
    if (f->inst_cos) {
        /* Embree reports Ng in the instanced (object) space. The instance's linear part is
         * s·R_y(a) with s uniform, so the world normal is R_y(a)·Ng (up to length, which the
         * shadow set-up normalises): (c·nx + s·nz, ny, −s·nx + c·nz). */
        for (int k = 0; k < 16; k++) {
            unsigned id = rh.hit.instID[0][k];
            if (!valid[k] || id >= f->ninst) continue;
            float cs = f->inst_cos[id], sn = f->inst_sin[id];
            float nx = rh.hit.Ng_x[k], nz = rh.hit.Ng_z[k];
            rh.hit.Ng_x[k] = cs * nx + sn * nz;
            rh.hit.Ng_z[k] = -sn * nx + cs * nz;
        }
    }

    /* shadow rays, branch-free over the 16 lanes (so that the compiler vectorises it) */
    const float lx = c->light[0], ly = c->light[1], lz = c->light[2];
    const float ox = c->org[0], oy = c->org[1], oz = c->org[2], omax = c->org_max;
    const int facing = o->shadow_facing ? -1 : 0;
    int cast_l[16], hit_l[16], backlit_l[16];
#pragma omp simd
    for (int k = 0; k < 16; k++) {
        int hit = valid[k] & -(rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID);
        float t = rh.ray.tfar[k];
        float dx = rh.ray.dir_x[k], dy = rh.ray.dir_y[k], dz = rh.ray.dir_z[k];
        float px = ox + t * dx, py = oy + t * dy, pz = oz + t * dz;
        float nx = rh.hit.Ng_x[k], ny = rh.hit.Ng_y[k], nz = rh.hit.Ng_z[k];
        float nn = MAXF((nx * nx + ny * ny) + nz * nz, 1e-30f);
        float inv = 1.0f / sqrtf(nn);
        float Lx = lx - px, Ly = ly - py, Lz = lz - pz;
        float ndl = (nx * Lx + ny * Ly) + nz * Lz;
        float ndd = (nx * dx + ny * dy) + nz * dz;
        int lit_side = -((ndd > 0.0f ? -ndl : ndl) > 0.0f); /* eye-facing normal · L > 0 */
        float scale = MAXF(MAXF(fabsf(px), fabsf(py)), MAXF(fabsf(pz), MAXF(t, omax)));
        float off = SHADOW_EPS * scale * inv;
        off = ndl < 0.0f ? -off : off; /* toward the light */
        float sx = px + nx * off, sy = py + ny * off, sz = pz + nz * off;
        float ex = lx - sx, ey = ly - sy, ez = lz - sz;
        float dist = sqrtf((ex * ex + ey * ey) + ez * ez);
        float rd = 1.0f / MAXF(dist, 1e-30f);
        sr.org_x[k] = sx; sr.org_y[k] = sy; sr.org_z[k] = sz;
        sr.dir_x[k] = ex * rd; sr.dir_y[k] = ey * rd; sr.dir_z[k] = ez * rd;
        sr.tnear[k] = 0.0f;
        sr.tfar[k] = dist;
        sr.time[k] = 0.0f;
        sr.mask[k] = 0xFFFFFFFFu;
        sr.id[k] = (unsigned)k;
        sr.flags[k] = 0;
        int cast = hit & (~facing | lit_side) & -(dist > 0.0f);
        svalid[k] = cast;
        cast_l[k] = cast & 1;
        hit_l[k] = hit & 1;
        backlit_l[k] = hit & facing & ~lit_side & 1;
    }
    int nshadow = 0, nhit = 0, nback = 0;
    for (int k = 0; k < 16; k++) { nshadow += cast_l[k]; nhit += hit_l[k]; nback += backlit_l[k]; }
    st->hits += (uint64_t)nhit;
    st->backlit += (uint64_t)nback;
    if (o->shadow_none) nshadow = 0;
    if (nshadow) {
        ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
        rtcOccluded16(svalid, f->scene, &ctx, &sr);
        st->shadow_rays += (uint64_t)nshadow;
        int nsh = 0;
        for (int k = 0; k < 16; k++) nsh += (svalid[k] & 1) & (sr.tfar[k] == -INFINITY);
        st->shadowed += (uint64_t)nsh;
    }
    if (f->depth || f->primid) {
        for (int k = 0; k < 16; k++) {
            if (!valid[k]) continue;
            size_t pix = (size_t)(ty * 4 + (k >> 2)) * W + (size_t)(tx * 4 + (k & 3));
            bool hit = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
            if (f->depth) {
                float t = rh.ray.tfar[k];
                if (o->depth_planar) /* t·(d·forward) */
                    t *= (rh.ray.dir_x[k] * c->fwd_f[0] + rh.ray.dir_y[k] * c->fwd_f[1]) + rh.ray.dir_z[k] * c->fwd_f[2];
                f->depth[pix] = hit ? t : INFINITY;
            }
            if (f->primid) f->primid[pix] = hit ? rh.hit.primID[k] : 0xFFFFFFFFu;
        }
    }
}

static void* worker_main(void* arg) {
    Worker* w = arg;
    Frame* f = w->f;
    for (;;) {
        int ty = __atomic_fetch_add(&f->next_row, 1, __ATOMIC_RELAXED);
        if (ty >= f->tiles_y) break;
        for (int tx = 0; tx < f->tiles_x; tx++) render_tile(f, tx, ty, &w->st);
    }
    return NULL;
}

static Stats render_frame(Frame* f, int threads) {
    f->next_row = 0;
    Worker* ws = xmalloc((size_t)threads * sizeof *ws);
    pthread_t* th = xmalloc((size_t)threads * sizeof *th);
    for (int t = 0; t < threads; t++) { ws[t].f = f; memset(&ws[t].st, 0, sizeof ws[t].st); }
    for (int t = 1; t < threads; t++)
        if (pthread_create(&th[t], NULL, worker_main, &ws[t])) die("pthread_create failed");
    worker_main(&ws[0]);
    for (int t = 1; t < threads; t++) pthread_join(th[t], NULL);
    Stats s = {0, 0, 0, 0};
    for (int t = 0; t < threads; t++) {
        s.hits += ws[t].st.hits; s.shadow_rays += ws[t].st.shadow_rays;
        s.shadowed += ws[t].st.shadowed; s.backlit += ws[t].st.backlit;
    }
    free(ws);
    free(th);
    return s;
}

/* ------------------------------------------------------------------------------------ */
/* Embree plumbing                                                                       */

static int64_t mem_now, mem_peak;

static bool memory_monitor(void* ptr, ssize_t bytes, bool post) {
    (void)ptr; (void)post;
    int64_t v = __atomic_add_fetch(&mem_now, (int64_t)bytes, __ATOMIC_RELAXED);
    int64_t p = __atomic_load_n(&mem_peak, __ATOMIC_RELAXED);
    while (v > p && !__atomic_compare_exchange_n(&mem_peak, &p, v, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {}
    return true;
}

static void embree_error(void* user, enum RTCError code, const char* str) {
    (void)user;
    die("embree error %d: %s", (int)code, str ? str : "");
}

static const char* quality_name(enum RTCBuildQuality q) {
    return q == RTC_BUILD_QUALITY_LOW ? "low" : q == RTC_BUILD_QUALITY_HIGH ? "high" : "medium";
}

/* s as a JSON string body (quotes and backslashes escaped, control characters dropped) */
static void json_escape(char* out, size_t cap, const char* s) {
    size_t n = 0;
    for (; *s && n + 3 < cap; s++) {
        if (*s == '"' || *s == '\\') { out[n++] = '\\'; out[n++] = *s; }
        else if ((unsigned char)*s >= 0x20) out[n++] = *s;
    }
    out[n] = 0;
}

static bool ends_with(const char* s, const char* suf) {
    size_t a = strlen(s), b = strlen(suf);
    return a >= b && !strcasecmp(s + a - b, suf);
}

/* the 1-minute load average at the start (-1 where /proc/loadavg is missing): others' work on
 * the same cores shows up in the wall times, not much in the CPU times */
static double loadavg1(void) {
    double l = -1;
    FILE* f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf", &l) != 1) l = -1;
        fclose(f);
    }
    return l;
}

int main(int argc, char** argv) {
    Options o = parse_args(argc, argv);
    double load_at_start = loadavg1();
    Camera cam = make_camera(&o);

    /* load */
    Mesh m;
    memset(&m, 0, sizeof m);
    double t0 = now_ms();
    if (ends_with(o.mesh, ".ply")) load_ply(o.mesh, &m);
    else if (ends_with(o.mesh, ".obj")) load_obj(o.mesh, &m);
    else die("%s: the mesh must end in .ply or .obj", o.mesh);
    double load_ms = now_ms() - t0;
    if (m.nt == 0) die("%s: no triangles", o.mesh);
    if (m.nt > 0xFFFFFFFFull) die("%s: more than 2^32 triangles", o.mesh);

    /* device: Embree's own (TBB) build threads limited to --threads */
    char cfg[64];
    snprintf(cfg, sizeof cfg, "threads=%d,set_affinity=0", o.threads);
    RTCDevice dev = rtcNewDevice(cfg);
    if (!dev) die("rtcNewDevice failed (error %d)", (int)rtcGetDeviceError(NULL));
    rtcSetDeviceErrorFunction(dev, embree_error, NULL);
    rtcSetDeviceMemoryMonitorFunction(dev, memory_monitor, NULL);

    /* instanced modes: --grid N (N*N instances) or --single-scale S (one). The mesh stays in its
     * file's coordinates (the BLAS), the instances place it in the world, and the rays are
     * world-space in both --rays modes (no camera-relative shift): origin (float)o, the light
     * (float)light; --rays only picks how the eye directions are computed. */
    const bool instanced = o.grid > 0 || o.single_scale > 0;
    const unsigned ninst = o.grid > 0 ? (unsigned)o.grid * (unsigned)o.grid : instanced ? 1u : 0u;
    float* xfm = NULL;
    float* inst_cos = NULL;
    float* inst_sin = NULL;
    if (instanced) {
        for (int k = 0; k < 3; k++) { cam.org[k] = (float)cam.pos[k]; cam.light[k] = (float)o.light[k]; }
        cam.org_max = fmaxf(fmaxf(fabsf(cam.org[0]), fabsf(cam.org[1])), fabsf(cam.org[2]));
        xfm = xmalloc((size_t)ninst * 12 * sizeof(float));
        inst_cos = xmalloc((size_t)ninst * sizeof(float));
        inst_sin = xmalloc((size_t)ninst * sizeof(float));
        for (unsigned i = 0; i < ninst; i++) {
            double sc, cs, sn, t[3];
            if (o.grid > 0) {
                /* instance i: scale S, then R_y((i·37) mod 360 degrees), then translate
                 * (i mod N + 0.5, 0, i div N + 0.5); sin and cos exact at multiples of 90 */
                const unsigned N = (unsigned)o.grid;
                int deg = (int)(((unsigned long long)i * 37u) % 360u);
                sc = o.grid_scale;
                if (deg % 90 == 0) {
                    static const double S4[4] = {0, 1, 0, -1}, C4[4] = {1, 0, -1, 0};
                    sn = S4[deg / 90]; cs = C4[deg / 90];
                } else {
                    double r = deg * (M_PI / 180.0);
                    sn = sin(r); cs = cos(r);
                }
                t[0] = (double)(i % N) + 0.5; t[1] = 0.0; t[2] = (double)(i / N) + 0.5;
            } else {
                sc = o.single_scale; cs = 1.0; sn = 0.0;
                for (int k = 0; k < 3; k++) t[k] = o.single_at[k];
            }
            /* 3x4 row major: world = M·p + t with M = s·R_y(a), R_y(a) = [[c,0,s],[0,1,0],[−s,0,c]] */
            float* x = xfm + 12 * (size_t)i;
            x[0] = (float)(sc * cs);  x[1] = 0.0f;        x[2] = (float)(sc * sn);  x[3] = (float)t[0];
            x[4] = 0.0f;              x[5] = (float)sc;   x[6] = 0.0f;              x[7] = (float)t[1];
            x[8] = (float)(-sc * sn); x[9] = 0.0f;        x[10] = (float)(sc * cs); x[11] = (float)t[2];
            inst_cos[i] = (float)cs;
            inst_sin[i] = (float)sn;
        }
    }

    RTCGeometry geom = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    float* vb = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.nv);
    uint32_t* ib = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), m.nt);
    /* f32 rays: the mesh is moved by −o in double, then rounded (rayreel's camera-relative f32);
     * instanced modes: the file's coordinates, rounded */
    for (size_t v = 0; v < 3 * m.nv; v++)
        vb[v] = (cam.f32 && !instanced) ? (float)(m.pos[v] - cam.pos[v % 3]) : (float)m.pos[v];
    memcpy(ib, m.tri, m.nt * 3 * sizeof(uint32_t));
    rtcSetGeometryBuildQuality(geom, o.quality);
    rtcCommitGeometry(geom);

    /* build --build-repeat times (a fresh scene each time; the first also starts TBB's pool) */
    double* builds = xmalloc((size_t)o.build_repeat * sizeof(double));
    double* builds_cpu = xmalloc((size_t)o.build_repeat * sizeof(double));
    RTCScene scene = NULL;
    int64_t mem_scene = 0;
    /* instanced: per build the BLAS commit, the instances' creation, the top-level commit */
    double* blas_ms = xmalloc((size_t)o.build_repeat * sizeof(double));
    double* blas_cpu = xmalloc((size_t)o.build_repeat * sizeof(double));
    double* top_ms = xmalloc((size_t)o.build_repeat * sizeof(double));
    double* top_cpu = xmalloc((size_t)o.build_repeat * sizeof(double));
    double* setup_ms = xmalloc((size_t)o.build_repeat * sizeof(double));
    RTCScene blas = NULL;
    for (int b = 0; b < o.build_repeat && instanced; b++) {
        if (scene) rtcReleaseScene(scene);
        if (blas) rtcReleaseScene(blas);
        int64_t before = __atomic_load_n(&mem_now, __ATOMIC_RELAXED);
        blas = new_scene(dev, &o);
        rtcAttachGeometry(blas, geom);
        commit_timed(blas, &blas_ms[b], &blas_cpu[b]);
        double ts = now_ms();
        scene = new_scene(dev, &o);
        for (unsigned i = 0; i < ninst; i++) {
            RTCGeometry inst = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(inst, blas);
            rtcSetGeometryTimeStepCount(inst, 1);
            rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, xfm + 12 * (size_t)i);
            rtcCommitGeometry(inst);
            rtcAttachGeometryByID(scene, inst, i);
            rtcReleaseGeometry(inst);
        }
        setup_ms[b] = now_ms() - ts;
        commit_timed(scene, &top_ms[b], &top_cpu[b]);
        builds[b] = blas_ms[b] + top_ms[b];
        builds_cpu[b] = blas_cpu[b] + top_cpu[b];
        mem_scene = __atomic_load_n(&mem_now, __ATOMIC_RELAXED) - before;
    }
    for (int b = 0; b < o.build_repeat && !instanced; b++) {
        if (scene) rtcReleaseScene(scene);
        int64_t before = __atomic_load_n(&mem_now, __ATOMIC_RELAXED);
        scene = new_scene(dev, &o);
        rtcAttachGeometry(scene, geom);
        commit_timed(scene, &builds[b], &builds_cpu[b]);
        mem_scene = __atomic_load_n(&mem_now, __ATOMIC_RELAXED) - before;
    }
    double build_first = builds[0];
    qsort(builds, (size_t)o.build_repeat, sizeof(double), cmp_double);
    double build_best = builds[0];
    double build_med = median(builds, o.build_repeat);
    double build_cpu_med = median(builds_cpu, o.build_repeat);
    char extra[1024] = "";
    if (instanced) {
        double blas_med = median(blas_ms, o.build_repeat), top_med = median(top_ms, o.build_repeat);
        double blas_best = blas_ms[0], top_best = top_ms[0]; /* sorted by median() */
        snprintf(extra, sizeof extra,
                 ",\"mode\":\"%s\",\"instances\":%u,\"grid\":%d,\"grid_scale\":%.9g,\"single_scale\":%.9g,"
                 "\"single_at\":[%.9g,%.9g,%.9g],\"instanced_triangles\":%llu,"
                 "\"blas_build_ms\":%.3f,\"blas_build_ms_median\":%.3f,\"top_build_ms\":%.3f,\"top_build_ms_median\":%.3f,"
                 "\"blas_build_cpu_ms_median\":%.3f,\"top_build_cpu_ms_median\":%.3f,\"instance_setup_ms_median\":%.3f,"
                 "\"camera_relative\":false",
                 o.grid > 0 ? "grid" : "single", ninst, o.grid, o.grid > 0 ? o.grid_scale : 0.0, o.single_scale,
                 o.single_at[0], o.single_at[1], o.single_at[2], (unsigned long long)m.nt * ninst,
                 blas_best, blas_med, top_best, top_med, median(blas_cpu, o.build_repeat),
                 median(top_cpu, o.build_repeat), median(setup_ms, o.build_repeat));
    }

    /* frames: one warm-up, then --repeat timed */
    size_t npix = (size_t)o.width * o.height;
    Frame f;
    memset(&f, 0, sizeof f);
    f.o = &o; f.cam = &cam; f.scene = scene;
    if (instanced) { f.inst_cos = inst_cos; f.inst_sin = inst_sin; f.ninst = ninst; }
    f.tiles_x = (o.width + 3) / 4; f.tiles_y = (o.height + 3) / 4;
    if (o.depth_out) f.depth = xmalloc(npix * sizeof(float));
    if (o.primid_out) f.primid = xmalloc(npix * sizeof(uint32_t));
    Stats st = render_frame(&f, o.threads);
    double* frames = xmalloc((size_t)o.repeat * sizeof(double));
    double* frames_cpu = xmalloc((size_t)o.repeat * sizeof(double));
    for (int r = 0; r < o.repeat; r++) {
        double tf = now_ms(), cf = cpu_ms();
        Stats s2 = render_frame(&f, o.threads);
        frames[r] = now_ms() - tf;
        frames_cpu[r] = cpu_ms() - cf;
        if (memcmp(&s2, &st, sizeof st)) die("frames differ between repeats (nondeterminism?)");
    }
    qsort(frames, (size_t)o.repeat, sizeof(double), cmp_double);
    double fbest = frames[0];
    double fmed = median(frames, o.repeat);
    double fcpu_med = median(frames_cpu, o.repeat);

    /* outputs */
    if (o.depth_out) {
        FILE* out = fopen(o.depth_out, "wb");
        if (!out) die("%s: %s", o.depth_out, strerror(errno));
        fprintf(out, "Pf\n%d %d\n-1.0\n", o.width, o.height);
        /* PFM stores scanlines bottom to top */
        for (int i = o.height - 1; i >= 0; i--)
            if (fwrite(f.depth + (size_t)i * o.width, sizeof(float), (size_t)o.width, out) != (size_t)o.width)
                die("%s: write error", o.depth_out);
        if (fclose(out)) die("%s: write error", o.depth_out);
    }
    if (o.primid_out) {
        FILE* out = fopen(o.primid_out, "wb");
        if (!out) die("%s: %s", o.primid_out, strerror(errno));
        if (fwrite(f.primid, sizeof(uint32_t), npix, out) != npix) die("%s: write error", o.primid_out);
        if (fclose(out)) die("%s: write error", o.primid_out);
    }

    char mesh_json[1024];
    json_escape(mesh_json, sizeof mesh_json, o.mesh);
    uint64_t rays = (uint64_t)npix + st.shadow_rays;
    if (instanced) {
        size_t n = strlen(extra);
        snprintf(extra + n, sizeof extra - n, ",\"hit_fraction\":%.6f", (double)st.hits / (double)npix);
    }
    printf("{\"triangles\":%zu,\"build_ms\":%.3f,\"frame_ms_best\":%.3f,\"frame_ms_median\":%.3f,"
           "\"fps\":%.3f,\"rays_per_s\":%.0f,\"hits\":%llu,\"shadowed\":%llu,"
           "\"shadow_rays\":%llu,\"backlit\":%llu,\"eye_rays\":%zu,\"vertices\":%zu,\"polygons\":%zu,"
           "\"build_ms_median\":%.3f,\"build_ms_first\":%.3f,\"build_cpu_ms_median\":%.3f,"
           "\"frame_cpu_ms_median\":%.3f,\"builds\":%d,\"frames\":%d,"
           "\"load_ms\":%.1f,\"bvh_mem_mb\":%.2f,\"embree_mem_peak_mb\":%.2f,"
           "\"loadavg_1m\":%.2f,\"width\":%d,\"height\":%d,\"threads\":%d,\"build_quality\":\"%s\",\"scene_flags\":\"%s\","
           "\"shadow\":\"%s\",\"rays\":\"%s\",\"embree\":\"%s\",\"native_ray16\":%s,\"mesh\":\"%s\"%s}\n",
           m.nt, build_best, fbest, fmed, 1000.0 / fmed, (double)rays / (fmed * 1e-3),
           (unsigned long long)st.hits, (unsigned long long)st.shadowed, (unsigned long long)st.shadow_rays,
           (unsigned long long)st.backlit, npix, m.nv, m.polygons, build_med, build_first, build_cpu_med, fcpu_med, o.build_repeat,
           o.repeat, load_ms, (double)mem_scene / (1 << 20), (double)mem_peak / (1 << 20), load_at_start, o.width, o.height,
           o.threads, quality_name(o.quality), o.robust ? "robust" : "none", o.shadow_none ? "none" : o.shadow_facing ? "facing" : "all", cam.f32 ? "f32" : "f64",
           RTC_VERSION_STRING, rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) ? "true" : "false",
           mesh_json, extra);

    rtcReleaseScene(scene);
    if (blas) rtcReleaseScene(blas);
    rtcReleaseGeometry(geom);
    rtcReleaseDevice(dev);
    free(m.pos); free(m.tri); free(builds); free(frames); free(builds_cpu); free(frames_cpu); free(f.depth); free(f.primid);
    free(cam.xs_d); free(cam.ys_d); free(cam.xs_f); free(cam.ys_f);
    free(blas_ms); free(blas_cpu); free(top_ms); free(top_cpu); free(setup_ms); free(xfm); free(inst_cos); free(inst_sin);
    return 0;
}

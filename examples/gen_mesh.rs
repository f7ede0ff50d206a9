//! Generates deterministic triangle meshes for rayreel's mesh tests and benchmarks (issue 26),
//! using only std.
//!
//! ```text
//! cargo run --release --example gen_mesh -- [--obj] sphere N OUT.ply     UV sphere, N bands
//! cargo run --release --example gen_mesh -- [--obj] terrain N OUT.ply    N×N heightfield
//! cargo run --release --example gen_mesh -- [--obj] blob K OUT.ply       displaced icosphere
//! cargo run --release --example gen_mesh -- [--obj] bunnyish [K] OUT.ply blob, K = 71 by default
//! cargo run --release --example gen_mesh -- [--obj] vase N OUT.ply       a z-up "scan", 50 tall
//! ```
//!
//! - `sphere N` (N ≥ 2): the unit sphere about the origin, N latitude bands × 2N longitude
//!   segments, 4N(N−1) triangles (one per quad at the poles, which are exact points), with
//!   per-vertex normals (the position) and uv (u = longitude / 2π from +z toward +x, v = 1 at
//!   the north pole +y, 0 at the south pole). The seam column repeats column 0's positions bit
//!   for bit, so the surface is watertight in its coordinates.
//! - `terrain N` (N ≥ 2): an N×N grid over x, z ∈ [−1, 1] with heights y from eight rotated
//!   octaves of sin·cos (|y| < 0.25), 2·(N−1)² triangles facing +y, normals from the height
//!   function's analytic gradient, uv = the grid position in [0, 1]². N = 1001 gives 2,000,000
//!   triangles.
//! - `blob K` (K ≥ 1): an icosahedron whose faces are split into K² triangles each (20·K²
//!   triangles; K = 71 gives 100,820), projected to the unit sphere, displaced radially by
//!   a sum of sin products and stretched to a lumpy, bunny-sized stand-in for a scanned model
//!   (closed, star-shaped, never self-intersecting), with area-weighted vertex normals.
//! - `vase N` (N ≥ 3): a vase turned about the z axis with a spout towards +x, 4N² + 2N
//!   triangles, written as a scan often comes: z up, 50 units tall, standing on z = 10 at
//!   (120, −40), for `up: z`, `fit` and `origin` to place (sequences/model.yaml).
//!
//! Output is binary little-endian PLY (`float x y z [nx ny nz] [u v]`, `face` with
//! `list uchar int vertex_indices`, triangles wound counter-clockwise seen from outside/above),
//! or Wavefront OBJ with `--obj` or an OUT ending in `.obj`. The bytes depend only on the
//! arguments: sin and cos are computed here with plain IEEE-754 arithmetic (no platform libm),
//! so every machine writes the same file.

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::process::ExitCode;

/// A triangle mesh in f64, rounded to f32 when written.
struct Mesh {
    pos: Vec<[f64; 3]>,
    normals: Option<Vec<[f64; 3]>>,
    uv: Option<Vec<[f64; 2]>>,
    tris: Vec<[u32; 3]>,
}

// ---------------------------------------------------------------------------------------
// Deterministic sin and cos: Cody–Waite reduction by π/2 (fdlibm's three-part constant) and
// Taylor polynomials on |r| ≤ π/4: within a few ulp for the |x| < 1e5 used here.

const PIO2_1: f64 = 1.570_796_326_734_125_6;
const PIO2_2: f64 = 6.077_100_506_303_966e-11;
const PIO2_3: f64 = 2.022_266_248_795_950_6e-21;

fn sin_cos(x: f64) -> (f64, f64) {
    let k = (x * std::f64::consts::FRAC_2_PI).round();
    let r = ((x - k * PIO2_1) - k * PIO2_2) - k * PIO2_3;
    let r2 = r * r;
    // sin r = r − r³/3! + … − r¹⁵/15!;  cos r = 1 − r²/2! + … + r¹⁶/16!
    let s = r + r
        * r2
        * (-1.0 / 6.0
            + r2 * (1.0 / 120.0
                + r2 * (-1.0 / 5040.0
                    + r2 * (1.0 / 362_880.0
                        + r2 * (-1.0 / 39_916_800.0
                            + r2 * (1.0 / 6_227_020_800.0 + r2 * (-1.0 / 1_307_674_368_000.0)))))));
    let c = 1.0
        + r2 * (-0.5
            + r2 * (1.0 / 24.0
                + r2 * (-1.0 / 720.0
                    + r2 * (1.0 / 40_320.0
                        + r2 * (-1.0 / 3_628_800.0
                            + r2 * (1.0 / 479_001_600.0
                                + r2 * (-1.0 / 87_178_291_200.0
                                    + r2 * (1.0 / 20_922_789_888_000.0))))))));
    match (k as i64).rem_euclid(4) {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

fn sin(x: f64) -> f64 {
    sin_cos(x).0
}

fn cos(x: f64) -> f64 {
    sin_cos(x).1
}

// ---------------------------------------------------------------------------------------
// vectors

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]
}

fn normalize(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    if l > 0.0 {
        [a[0] / l, a[1] / l, a[2] / l]
    } else {
        [0.0, 0.0, 0.0]
    }
}

/// Area-weighted vertex normals: the sum of the faces' cross products, normalised.
fn vertex_normals(pos: &[[f64; 3]], tris: &[[u32; 3]]) -> Vec<[f64; 3]> {
    let mut n = vec![[0.0f64; 3]; pos.len()];
    for t in tris {
        let (a, b, c) = (pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize]);
        let f = cross(sub(b, a), sub(c, a));
        for &v in t {
            let m = &mut n[v as usize];
            m[0] += f[0];
            m[1] += f[1];
            m[2] += f[2];
        }
    }
    n.into_iter().map(normalize).collect()
}

/// A mesh of `pos` and `tris` with area-weighted vertex normals and no uv.
fn with_normals(pos: Vec<[f64; 3]>, tris: Vec<[u32; 3]>) -> Mesh {
    let normals = vertex_normals(&pos, &tris);
    Mesh {
        pos,
        normals: Some(normals),
        uv: None,
        tris,
    }
}

// ---------------------------------------------------------------------------------------
// generators

fn sphere(n: usize) -> Mesh {
    let segs = 2 * n;
    let cols = segs + 1;
    let mut pos = Vec::with_capacity((n + 1) * cols);
    let mut uv = Vec::with_capacity((n + 1) * cols);
    let pi = std::f64::consts::PI;
    for i in 0..=n {
        let (st, ct) = sin_cos(pi * i as f64 / n as f64);
        for j in 0..cols {
            let p = if i == 0 {
                [0.0, 1.0, 0.0]
            } else if i == n {
                [0.0, -1.0, 0.0]
            } else {
                // the seam column j = segs takes column 0's angle exactly
                let (sp, cp) = sin_cos(2.0 * pi * (j % segs) as f64 / segs as f64);
                [st * sp, ct, st * cp]
            };
            pos.push(p);
            uv.push([j as f64 / segs as f64, 1.0 - i as f64 / n as f64]);
        }
    }
    let mut tris = Vec::with_capacity(4 * n * (n - 1));
    let at = |i: usize, j: usize| (i * cols + j) as u32;
    for i in 0..n {
        for j in 0..segs {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            // at the south pole row b = c, at the north pole row a = d: one triangle each
            if i != n - 1 {
                tris.push([a, b, c]);
            }
            if i != 0 {
                tris.push([a, c, d]);
            }
        }
    }
    let normals = pos.clone();
    Mesh {
        pos,
        normals: Some(normals),
        uv: Some(uv),
        tris,
    }
}

/// The terrain's height and its gradient (dh/dx, dh/dz) at (x, z).
struct Terrain {
    octaves: Vec<(f64, f64, f64, f64, f64, f64)>, // amplitude, frequency, cos θ, sin θ, phase u, phase v
}

impl Terrain {
    fn new() -> Terrain {
        let octaves = (0..8)
            .map(|o| {
                let o = o as f64;
                let (s, c) = sin_cos(0.7 + 1.3 * o);
                (
                    0.11 * 0.5f64.powi(o as i32),
                    3.1 * 1.93f64.powi(o as i32),
                    c,
                    s,
                    0.37 * o + 0.2,
                    1.11 * o + 0.5,
                )
            })
            .collect();
        Terrain { octaves }
    }

    fn eval(&self, x: f64, z: f64) -> (f64, f64, f64) {
        let (mut h, mut hx, mut hz) = (0.0, 0.0, 0.0);
        for &(a, f, c, s, pu, pv) in &self.octaves {
            // rotated coordinates u, v of this octave
            let u = c * x - s * z;
            let v = s * x + c * z;
            let (su, cu) = sin_cos(f * u + pu);
            let (sv, cv) = sin_cos(f * v + pv);
            h += a * su * cv;
            let du = a * f * cu * cv; // dh/du
            let dv = -a * f * su * sv; // dh/dv
            hx += du * c + dv * s;
            hz += -du * s + dv * c;
        }
        (h, hx, hz)
    }
}

fn terrain(n: usize) -> Mesh {
    let t = Terrain::new();
    let mut pos = Vec::with_capacity(n * n);
    let mut normals = Vec::with_capacity(n * n);
    let mut uv = Vec::with_capacity(n * n);
    let step = (n - 1) as f64;
    for i in 0..n {
        let z = -1.0 + 2.0 * i as f64 / step;
        for j in 0..n {
            let x = -1.0 + 2.0 * j as f64 / step;
            let (h, hx, hz) = t.eval(x, z);
            pos.push([x, h, z]);
            normals.push(normalize([-hx, 1.0, -hz]));
            uv.push([j as f64 / step, i as f64 / step]);
        }
    }
    let mut tris = Vec::with_capacity(2 * (n - 1) * (n - 1));
    let at = |i: usize, j: usize| (i * n + j) as u32;
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    Mesh {
        pos,
        normals: Some(normals),
        uv: Some(uv),
        tris,
    }
}

/// Radius of the blob in unit direction u.
fn blob_radius(u: [f64; 3]) -> f64 {
    let [x, y, z] = u;
    let f1 = sin(2.3 * x + 0.4) * cos(1.9 * y - 0.7) * sin(2.7 * z + 1.3);
    let f2 = sin(5.1 * x + 3.9 * y + 0.2) * cos(4.3 * z - 2.9 * y + 0.9);
    let f3 = sin(13.7 * x + 1.0) * sin(11.3 * y + 2.0) * sin(12.1 * z + 3.0);
    let f4 = sin(31.0 * x + 17.0 * z + 0.5) * cos(29.0 * y - 0.3);
    1.0 + 0.25 * f1 + 0.08 * f2 + 0.025 * f3 + 0.006 * f4
}

fn blob(k: usize) -> Mesh {
    let g = (1.0 + 5.0f64.sqrt()) / 2.0;
    let corners: [[f64; 3]; 12] = [
        [-1.0, g, 0.0],
        [1.0, g, 0.0],
        [-1.0, -g, 0.0],
        [1.0, -g, 0.0],
        [0.0, -1.0, g],
        [0.0, 1.0, g],
        [0.0, -1.0, -g],
        [0.0, 1.0, -g],
        [g, 0.0, -1.0],
        [g, 0.0, 1.0],
        [-g, 0.0, -1.0],
        [-g, 0.0, 1.0],
    ];
    let mut faces: [[usize; 3]; 20] = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for f in faces.iter_mut() {
        let (a, b, c) = (corners[f[0]], corners[f[1]], corners[f[2]]);
        let centre = [a[0] + b[0] + c[0], a[1] + b[1] + c[1], a[2] + b[2] + c[2]];
        if dot(cross(sub(b, a), sub(c, a)), centre) < 0.0 {
            f.swap(1, 2);
        }
    }
    // A vertex is named by its corners and integer weights (summing to k), sorted by corner,
    // so the faces sharing an edge or a corner find the same vertex and compute the same bits.
    let mut index: HashMap<[(u32, u32); 3], u32> = HashMap::new();
    let mut pos: Vec<[f64; 3]> = Vec::new();
    let mut vertex = |w: [(usize, usize); 3]| -> u32 {
        let mut key: Vec<(u32, u32)> = w
            .iter()
            .filter(|&&(_, wt)| wt > 0)
            .map(|&(c, wt)| (c as u32, wt as u32))
            .collect();
        key.sort();
        while key.len() < 3 {
            key.push((u32::MAX, 0));
        }
        let key = [key[0], key[1], key[2]];
        *index.entry(key).or_insert_with(|| {
            let mut p = [0.0f64; 3];
            for &(c, wt) in key.iter().filter(|e| e.1 > 0) {
                for q in 0..3 {
                    p[q] += wt as f64 * corners[c as usize][q];
                }
            }
            let u = normalize(p);
            let r = blob_radius(u);
            pos.push([1.15 * r * u[0], 0.9 * r * u[1], r * u[2]]);
            (pos.len() - 1) as u32
        })
    };
    let mut tris = Vec::with_capacity(20 * k * k);
    for f in &faces {
        // row r = 0..=k from corner A, s = 0..=r: weights A = k − r, B = r − s, C = s
        let p = |r: usize, s: usize| [(f[0], k - r), (f[1], r - s), (f[2], s)];
        for r in 0..k {
            for s in 0..=r {
                let (a, b, c) = (
                    vertex(p(r, s)),
                    vertex(p(r + 1, s)),
                    vertex(p(r + 1, s + 1)),
                );
                tris.push([a, b, c]);
                if s < r {
                    let d = vertex(p(r, s + 1));
                    tris.push([a, c, d]);
                }
            }
        }
    }
    with_normals(pos, tris)
}

/// A vase turned about the z axis, as a scan would come: z up, 50 units tall, standing on
/// z = 10 at (120, −40), its profile r(t) = 5.5 + 8·sin(πt/0.85) (0 above t = 0.85) +
/// 3·max(0, (t − 0.8)/0.2)² − 1.5t over t ∈ [0, 1] from foot to lip, `n` segments around
/// and 2n rings, its foot and lip closed by
/// fans to points on the axis; a spout on one side (+x, bulging the rings there) shows which
/// way it faces.
fn vase(n: usize) -> Mesh {
    let rings = 2 * n;
    let (cx, cy, z0, height) = (120.0, -40.0, 10.0, 50.0);
    let mut pos = Vec::with_capacity((rings + 1) * n + 2);
    for i in 0..=rings {
        let t = i as f64 / rings as f64;
        // A foot, a belly, a narrow neck and a flared lip.
        let belly = if t < 0.85 {
            sin(std::f64::consts::PI * t / 0.85)
        } else {
            0.0
        };
        let lip = ((t - 0.8) / 0.2).max(0.0);
        let r = 5.5 + 8.0 * belly + 3.0 * lip * lip - 1.5 * t;
        for j in 0..n {
            let a = std::f64::consts::TAU * j as f64 / n as f64;
            let (s, c) = sin_cos(a);
            // The spout: the upper rings reach out towards +x.
            let spout = 5.0 * t * t * t * t * c.max(0.0).powi(6);
            pos.push([cx + (r + spout) * c, cy + (r + spout) * s, z0 + height * t]);
        }
    }
    pos.push([cx, cy, z0]);
    pos.push([cx, cy, z0 + height]);
    let (foot, lip) = ((pos.len() - 2) as u32, (pos.len() - 1) as u32);
    let at = |i: usize, j: usize| (i * n + j % n) as u32;
    let mut tris = Vec::with_capacity(2 * rings * n + 2 * n);
    for i in 0..rings {
        for j in 0..n {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    for j in 0..n {
        tris.push([foot, at(0, j + 1), at(0, j)]);
        tris.push([lip, at(rings, j), at(rings, j + 1)]);
    }
    with_normals(pos, tris)
}

// ---------------------------------------------------------------------------------------
// writers

fn write_ply(m: &Mesh, out: &mut impl Write, comment: &str) -> std::io::Result<()> {
    let mut h = String::from("ply\nformat binary_little_endian 1.0\n");
    h += &format!("comment {comment}\n");
    h += &format!(
        "element vertex {}\nproperty float x\nproperty float y\nproperty float z\n",
        m.pos.len()
    );
    if m.normals.is_some() {
        h += "property float nx\nproperty float ny\nproperty float nz\n";
    }
    if m.uv.is_some() {
        h += "property float u\nproperty float v\n";
    }
    h += &format!(
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        m.tris.len()
    );
    out.write_all(h.as_bytes())?;
    for (i, p) in m.pos.iter().enumerate() {
        let mut v = [
            p[0] as f32,
            p[1] as f32,
            p[2] as f32,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
        ];
        let mut n = 3;
        if let Some(ns) = &m.normals {
            v[n..n + 3].copy_from_slice(&[ns[i][0] as f32, ns[i][1] as f32, ns[i][2] as f32]);
            n += 3;
        }
        if let Some(uv) = &m.uv {
            v[n..n + 2].copy_from_slice(&[uv[i][0] as f32, uv[i][1] as f32]);
            n += 2;
        }
        for x in &v[..n] {
            out.write_all(&x.to_le_bytes())?;
        }
    }
    for t in &m.tris {
        let mut b = [0u8; 13];
        b[0] = 3;
        for (q, &v) in t.iter().enumerate() {
            b[1 + 4 * q..5 + 4 * q].copy_from_slice(&(v as i32).to_le_bytes());
        }
        out.write_all(&b)?;
    }
    Ok(())
}

fn write_obj(m: &Mesh, out: &mut impl Write, comment: &str) -> std::io::Result<()> {
    writeln!(out, "# {comment}")?;
    for p in &m.pos {
        writeln!(out, "v {} {} {}", p[0] as f32, p[1] as f32, p[2] as f32)?;
    }
    if let Some(ns) = &m.normals {
        for n in ns {
            writeln!(out, "vn {} {} {}", n[0] as f32, n[1] as f32, n[2] as f32)?;
        }
    }
    if let Some(uv) = &m.uv {
        for t in uv {
            writeln!(out, "vt {} {}", t[0] as f32, t[1] as f32)?;
        }
    }
    for t in &m.tris {
        let [a, b, c] = t.map(|v| v + 1);
        match (m.uv.is_some(), m.normals.is_some()) {
            (true, true) => writeln!(out, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}")?,
            (false, true) => writeln!(out, "f {a}//{a} {b}//{b} {c}//{c}")?,
            (true, false) => writeln!(out, "f {a}/{a} {b}/{b} {c}/{c}")?,
            (false, false) => writeln!(out, "f {a} {b} {c}")?,
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------

const USAGE: &str = "usage: gen_mesh [--obj] sphere N OUT | terrain N OUT | blob K OUT | bunnyish [K] OUT | vase N OUT\n\
                     (OUT ending in .obj, or --obj, writes Wavefront OBJ; else binary PLY)";

fn parse_count(s: &str, what: &str, lo: usize, hi: usize) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        _ => Err(format!(
            "{what} must be a whole number in [{lo}, {hi}], got '{s}'"
        )),
    }
}

fn run() -> Result<(), String> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let obj_flag = args.iter().any(|a| a == "--obj");
    args.retain(|a| a != "--obj");
    if args.iter().any(|a| a == "-h" || a == "--help") || args.is_empty() {
        return Err(USAGE.to_string());
    }
    let kind = args[0].as_str();
    let (mesh, out, comment) = match (kind, args.len()) {
        ("sphere", 3) => {
            // 4N(N−1) triangles and (N+1)(2N+1) vertices must fit a PLY int
            let n = parse_count(&args[1], "N", 2, 16_000)?;
            (sphere(n), &args[2], format!("rayreel gen_mesh sphere {n}"))
        }
        ("terrain", 3) => {
            let n = parse_count(&args[1], "N", 2, 40_000)?;
            (
                terrain(n),
                &args[2],
                format!("rayreel gen_mesh terrain {n}"),
            )
        }
        ("blob", 3) | ("bunnyish", 3) => {
            let k = parse_count(&args[1], "K", 1, 10_000)?;
            (blob(k), &args[2], format!("rayreel gen_mesh blob {k}"))
        }
        ("bunnyish", 2) => (blob(71), &args[1], "rayreel gen_mesh blob 71".to_string()),
        ("vase", 3) => {
            let n = parse_count(&args[1], "N", 3, 10_000)?;
            (vase(n), &args[2], format!("rayreel gen_mesh vase {n}"))
        }
        _ => return Err(USAGE.to_string()),
    };
    let obj = obj_flag || out.to_ascii_lowercase().ends_with(".obj");
    let file = File::create(out).map_err(|e| format!("{out}: {e}"))?;
    let mut w = BufWriter::with_capacity(1 << 20, file);
    let res = if obj {
        write_obj(&mesh, &mut w, &comment)
    } else {
        write_ply(&mesh, &mut w, &comment)
    };
    res.and_then(|_| w.flush())
        .map_err(|e| format!("{out}: {e}"))?;
    eprintln!(
        "gen_mesh: wrote {out} ({}): {} vertices, {} triangles",
        if obj { "OBJ" } else { "binary PLY" },
        mesh.pos.len(),
        mesh.tris.len()
    );
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("gen_mesh: {e}");
            ExitCode::from(2)
        }
    }
}

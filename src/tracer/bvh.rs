//! The hierarchy of one mesh file, in the mesh's own coordinates: built once per file and
//! shared by every placement (`accel::wide`, 4-wide nodes with f32 boxes over the triangles'
//! boxes), with the triangles copied in leaf order in the precision a frame tests them in:
//! f64 triangles for f64 frames, the same values rounded to f32 once for f32 frames (what
//! docs/spec/mesh.md says each test rounds as it enters). Each copy is made the first time a
//! frame of its precision needs it, so a job pays only for the precision it renders in.

use super::accel::wide::{Prim, Tree};
use crate::scene::Mesh;
use glam::DVec3;
use std::sync::{Arc, OnceLock};

/// A triangle as f64 frames test it: vertices in mesh coordinates, the unnormalised normal
/// (v1 − v0) × (v2 − v0), and its index in the mesh's triangle list.
#[derive(Debug, Clone, Copy)]
pub struct Tri {
    pub v: [DVec3; 3],
    pub n: DVec3,
    pub id: u32,
}

/// The same triangle with every value rounded to f32 (to nearest), as f32 frames test it.
#[derive(Debug, Clone, Copy)]
pub struct Tri32 {
    pub v: [[f32; 3]; 3],
    pub n: [f32; 3],
    pub id: u32,
}

#[derive(Debug)]
pub struct Bvh {
    pub tree: Tree,
    /// The centre and size of the box of the vertices the triangles use (f32 frames start
    /// their tests near the centre: docs/spec/mesh.md, "f32 frames").
    pub centre: DVec3,
    pub extent: DVec3,
    mesh: Arc<Mesh>,
    tris: OnceLock<Vec<Tri>>,
    tris32: OnceLock<Vec<Tri32>>,
}

impl Bvh {
    pub fn build(mesh: &Arc<Mesh>) -> Bvh {
        use rayon::prelude::*;
        let p = &mesh.positions;
        let prims = mesh
            .triangles
            .par_iter()
            .enumerate()
            .map(|(i, t)| {
                let v = t.map(|k| p[k as usize]);
                Prim::new(v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]), i as u32)
            })
            .collect();
        let (lo, hi) = mesh.bounds();
        Bvh {
            tree: Tree::build(prims),
            centre: (lo + hi) * 0.5,
            extent: hi - lo,
            mesh: mesh.clone(),
            tris: OnceLock::new(),
            tris32: OnceLock::new(),
        }
    }

    /// The root's box (padded).
    pub fn bounds(&self) -> (DVec3, DVec3) {
        (self.tree.lo.as_dvec3(), self.tree.hi.as_dvec3())
    }

    /// The triangles in leaf order, in f64.
    #[inline]
    pub fn tris(&self) -> &[Tri] {
        self.tris.get_or_init(|| self.copy(|t| t))
    }

    /// The triangles in leaf order, rounded to f32.
    #[inline]
    pub fn tris32(&self) -> &[Tri32] {
        self.tris32.get_or_init(|| {
            self.copy(|t| Tri32 {
                v: t.v.map(|v| v.as_vec3().to_array()),
                n: t.n.as_vec3().to_array(),
                id: t.id,
            })
        })
    }

    /// The copy is written straight into one vector of its exact size: rayon's `collect`
    /// gathers pieces and then moves them into one, holding the copy twice at its peak (2M
    /// triangles in f64: 416 MB for 208), beyond what the budget counts.
    fn copy<T: Send>(&self, f: impl Fn(Tri) -> T + Sync + Send) -> Vec<T> {
        use rayon::prelude::*;
        let m = &self.mesh;
        let mut out = Vec::new();
        self.tree
            .order
            .par_iter()
            .map(|&i| {
                let v = m.triangles[i as usize].map(|k| m.positions[k as usize]);
                f(Tri {
                    v,
                    n: (v[1] - v[0]).cross(v[2] - v[0]),
                    id: i,
                })
            })
            .collect_into_vec(&mut out);
        out
    }

    /// Bytes the hierarchy and the triangle copies made so far hold (for `check`).
    pub fn bytes(&self) -> usize {
        self.tree.bytes()
            + self.tris.get().map_or(0, |t| t.len() * size_of::<Tri>())
            + self
                .tris32
                .get()
                .map_or(0, |t| t.len() * size_of::<Tri32>())
    }

    /// Bytes a triangle copy in f32 (`single`) or f64 takes per triangle.
    pub fn tri_bytes(single: bool) -> usize {
        if single {
            size_of::<Tri32>()
        } else {
            size_of::<Tri>()
        }
    }
}

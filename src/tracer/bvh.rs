//! The hierarchy of one mesh file, in the mesh's own coordinates: built once per file and
//! shared by every placement (`accel::wide`, 4-wide nodes with f32 boxes over the triangles'
//! boxes), with the triangles copied in leaf order in the precision a frame tests them in:
//! f64 triangles for f64 frames, the same values rounded to f32 once for f32 frames (what
//! docs/spec/mesh.md says each test rounds as it enters). Each copy is made before the first
//! frame of its precision (`prepare`), so a job pays only for the precisions it renders in;
//! the hierarchy and the copies are allocated fallibly, so that a system that refuses the
//! memory gets a message naming the mesh rather than an abort.

use super::accel::wide::{Prim, Tree};
use crate::budget::{self, OutOfMemory};
use crate::scene::Mesh;
use glam::DVec3;
use std::sync::{Arc, Mutex, OnceLock};

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
    /// Seconds the build took (`check` prints them).
    pub seconds: f64,
    mesh: Arc<Mesh>,
    tris: OnceLock<Vec<Tri>>,
    tris32: OnceLock<Vec<Tri32>>,
    /// Held while a copy is made, so that two frames starting at once do not both make it.
    copying: Mutex<()>,
}

impl Bvh {
    /// The hierarchy of `mesh`; an error naming the mesh when the system refuses its memory.
    pub fn build(mesh: &Arc<Mesh>) -> Result<Bvh, OutOfMemory> {
        use rayon::prelude::*;
        let started = std::time::Instant::now();
        let p = &mesh.positions;
        let what = || format!("the hierarchy of {}", mesh.file.display());
        let mut prims = Vec::new();
        reserve(&mut prims, mesh.triangles.len(), what)?;
        mesh.triangles
            .par_iter()
            .enumerate()
            .map(|(i, t)| {
                let v = t.map(|k| p[k as usize]);
                Prim::new(v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]), i as u32)
            })
            .collect_into_vec(&mut prims);
        let bytes = prims.len() * size_of::<Prim>();
        let tree = Tree::try_build(prims).map_err(|_| budget::refused(bytes as u64, what()))?;
        let (lo, hi) = mesh.bounds();
        Ok(Bvh {
            tree,
            centre: (lo + hi) * 0.5,
            extent: hi - lo,
            seconds: started.elapsed().as_secs_f64(),
            mesh: mesh.clone(),
            tris: OnceLock::new(),
            tris32: OnceLock::new(),
            copying: Mutex::new(()),
        })
    }

    /// Makes the copy of the triangles a frame in f32 (`single`) or f64 tests, unless made
    /// already: admitted by the memory budget, then allocated without aborting.
    pub fn prepare(&self, single: bool) -> Result<(), OutOfMemory> {
        let made = |b: &Bvh| match single {
            true => b.tris32.get().is_some(),
            false => b.tris.get().is_some(),
        };
        if made(self) {
            return Ok(());
        }
        let _one = self.copying.lock().unwrap_or_else(|e| e.into_inner());
        if made(self) {
            return Ok(());
        }
        let what = || {
            format!(
                "the {} copy of the {} triangles of {}",
                if single { "f32" } else { "f64" },
                self.tree.order.len(),
                self.mesh.file.display()
            )
        };
        match single {
            true => {
                let copy = self.copy(what, to_f32)?;
                let _ = self.tris32.set(copy);
            }
            false => {
                let copy = self.copy(what, |t| t)?;
                let _ = self.tris.set(copy);
            }
        }
        Ok(())
    }

    /// The root's box (padded).
    pub fn bounds(&self) -> (DVec3, DVec3) {
        (self.tree.lo.as_dvec3(), self.tree.hi.as_dvec3())
    }

    /// The triangles in leaf order, in f64: made by `prepare(false)`, which every frame
    /// calls first; for callers that did not, made here (and an allocation the system
    /// refuses then ends the process, as before).
    #[inline]
    pub fn tris(&self) -> &[Tri] {
        self.tris.get_or_init(|| self.copy_or_panic(|t| t))
    }

    /// The triangles in leaf order, rounded to f32 (`prepare(true)`, as for `tris`).
    #[inline]
    pub fn tris32(&self) -> &[Tri32] {
        self.tris32.get_or_init(|| self.copy_or_panic(to_f32))
    }

    #[cold]
    fn copy_or_panic<T: Send>(&self, f: impl Fn(Tri) -> T + Sync + Send) -> Vec<T> {
        let what = || format!("the triangles of {}", self.mesh.file.display());
        self.copy(what, f).unwrap_or_else(|e| panic!("{e}"))
    }

    /// The copy is written straight into one vector of its exact size: rayon's `collect`
    /// gathers pieces and then moves them into one, holding the copy twice at its peak (2M
    /// triangles in f64: 416 MB for 208), beyond what the budget counts.
    fn copy<T: Send>(
        &self,
        what: impl Fn() -> String,
        f: impl Fn(Tri) -> T + Sync + Send,
    ) -> Result<Vec<T>, OutOfMemory> {
        use rayon::prelude::*;
        let m = &self.mesh;
        let mut out = Vec::new();
        let n = self.tree.order.len();
        budget::admit((n * size_of::<T>()) as u64, &what)?;
        reserve(&mut out, n, what)?;
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
        Ok(out)
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

/// A triangle rounded to f32, value by value.
fn to_f32(t: Tri) -> Tri32 {
    Tri32 {
        v: t.v.map(|v| v.as_vec3().to_array()),
        n: t.n.as_vec3().to_array(),
        id: t.id,
    }
}

/// Room for exactly `n` elements in the empty `v`, or what the allocator refused, named.
fn reserve<T>(v: &mut Vec<T>, n: usize, what: impl Fn() -> String) -> Result<(), OutOfMemory> {
    v.try_reserve_exact(n)
        .map_err(|_| budget::refused((n * size_of::<T>()) as u64, what()))
}

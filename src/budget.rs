//! The one memory budget of a job: what the process may still take, read from the system each
//! time it is asked (the smallest of the cgroup's memory.max less its memory.current,
//! RLIMIT_AS less the address space mapped now, and MemAvailable), and checked before every
//! allocation that could exceed it: a texture's texels and mip pyramid before it is decoded, a
//! mesh's arrays each time one grows, a mesh's hierarchy before it is built, and the frames in
//! flight before the first starts (`schedule::memory`). A refusal names what needed the memory
//! and both figures, and the job exits 1, where an allocation that fails aborts the process
//! (exit 134) and the kernel's out-of-memory killer ends it without a word.

/// Bytes a triangle takes once traced: its share of the bottom-level hierarchy (nodes and the
/// triangles stored in its leaves), counted before the hierarchy is built. Update with the
/// hierarchy: conservative for today's (`check` prints its real size per mesh). Measured
/// 2026-11-27 on a 2M-triangle grid: nodes and order 46 bytes a triangle, the f64 copy of
/// the triangles 104 (the f32 one 52); while building, 28 for the boxes and the nodes twice.
pub(crate) const HIERARCHY_BYTES_PER_TRIANGLE: u64 = 160;

/// Bytes a triangle's f32 copy takes (`tracer::bvh::Tri32`), made beside the f64 one.
pub(crate) const F32_COPY_BYTES_PER_TRIANGLE: u64 = 52;

/// What a mesh of `triangles` triangles adds once its hierarchy is built and its triangles
/// copied in f64, and in f32 too for an f32 job (`both`): its frames that f32 cannot resolve
/// or whose things move, and its compositing passes, are traced in f64.
pub(crate) fn hierarchy_bytes(triangles: u64, both: bool) -> u64 {
    let each = HIERARCHY_BYTES_PER_TRIANGLE + u64::from(both) * F32_COPY_BYTES_PER_TRIANGLE;
    triangles.saturating_mul(each)
}

/// Room kept free under every limit for what no check counts (small vectors, the allocator's
/// own bookkeeping, the stack), so that a check that passes leaves the process able to go on.
const HEADROOM: u64 = 32 << 20;

/// What the process may still take: the tightest limit, less `HEADROOM`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Free {
    pub(crate) bytes: u64,
    /// The limit that decides it, in words (`RLIMIT_AS (ulimit -v)`).
    pub(crate) limit: &'static str,
    /// That limit's own value, for messages (`RLIMIT_AS (ulimit -v) of 3.00 GB`).
    pub(crate) of: u64,
}

/// The address space each thread the job will start reserves (see `schedule::memory`), kept
/// under RLIMIT_AS only: reserved address space is not memory a cgroup or MemAvailable counts.
pub(crate) fn free(reserved_address_space: u64) -> Option<Free> {
    let limits = [
        (cgroup(), 0, "the cgroup's memory.max"),
        (
            address_space(),
            reserved_address_space,
            "RLIMIT_AS (ulimit -v)",
        ),
        (mem_available(), 0, "MemAvailable in /proc/meminfo"),
    ];
    limits
        .into_iter()
        .filter_map(|(limit, reserved, what)| {
            let (left, of) = limit?;
            let bytes = left.saturating_sub(reserved + HEADROOM);
            Some(Free {
                bytes,
                limit: what,
                of,
            })
        })
        .min_by_key(|f| f.bytes)
}

/// Why something could not be given memory: what it was, and the figures.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("not enough memory for {what}: it needs about {} more, and only {} is free under {} of {}{}", size(*need), size(free.bytes), free.limit, size(free.of), taken.as_ref().map(|t| format!(" ({t})")).unwrap_or_default())]
pub struct OutOfMemory {
    pub(crate) what: String,
    pub(crate) need: u64,
    pub(crate) free: Free,
    /// What the job already holds, in words, when that helps to see why.
    pub(crate) taken: Option<String>,
}

/// `Ok` when `need` more bytes fit in what the process may take now; otherwise the figures.
/// `what` names the allocation (`decoding textures/wood.png (8192x8192) and its mip pyramid`).
pub(crate) fn admit(need: u64, what: impl FnOnce() -> String) -> Result<(), OutOfMemory> {
    match free(0) {
        Some(free) if need > free.bytes => Err(OutOfMemory {
            what: what(),
            need,
            free,
            taken: None,
        }),
        _ => Ok(()),
    }
}

/// Makes room in `v` for `more` elements: the next capacity (doubled, as `Vec` grows) is
/// admitted first, then reserved without aborting when the system still says no.
pub(crate) fn grow<T>(
    v: &mut Vec<T>,
    more: usize,
    what: impl Fn() -> String,
) -> Result<(), OutOfMemory> {
    if v.capacity() - v.len() >= more {
        return Ok(());
    }
    let wanted = v.len().saturating_add(more).max(2 * v.capacity()).max(16);
    let bytes = (wanted as u64).saturating_mul(std::mem::size_of::<T>() as u64);
    // Small vectors are not worth a look at /proc.
    if bytes >= 1 << 20 {
        admit(bytes, &what)?;
    }
    v.try_reserve_exact(wanted - v.len())
        .map_err(|_| refused(bytes, what()))
}

/// The allocator refused `need` bytes for `what` (after the budget admitted them, or for
/// what it does not look at): the figures as the budget reads them now.
pub(crate) fn refused(need: u64, what: String) -> OutOfMemory {
    OutOfMemory {
        what,
        need,
        free: free(0).unwrap_or(Free {
            bytes: 0,
            limit: "the allocator",
            of: 0,
        }),
        taken: None,
    }
}

/// `3.22 GB`, `153.2 MB`, `12.3 kB`, `512 bytes`: SI units, three significant figures or so,
/// so that no figure reads as 0.00.
pub(crate) fn size(bytes: u64) -> String {
    let b = bytes as f64;
    match bytes {
        n if n >= 1_000_000_000 => format!("{:.2} GB", b / 1e9),
        n if n >= 1_000_000 => format!("{:.1} MB", b / 1e6),
        n if n >= 1_000 => format!("{:.1} kB", b / 1e3),
        n => format!("{n} bytes"),
    }
}

/// (memory.max less memory.current, memory.max) of this process's cgroup (v2), when it has a
/// limit.
fn cgroup() -> Option<(u64, u64)> {
    let line = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let path = line.lines().find_map(|l| l.strip_prefix("0::"))?;
    let dir = std::path::Path::new("/sys/fs/cgroup").join(path.trim_start_matches('/'));
    let read = |name: &str| std::fs::read_to_string(dir.join(name)).ok();
    let max: u64 = read("memory.max")?.trim().parse().ok()?;
    let current: u64 = read("memory.current")?.trim().parse().unwrap_or(0);
    Some((max.saturating_sub(current), max))
}

/// (RLIMIT_AS less the address space this process has mapped now (VmSize), RLIMIT_AS).
fn address_space() -> Option<(u64, u64)> {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit only writes the struct it is given, which lives through the call.
    if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) } != 0
        || limit.rlim_cur == libc::RLIM_INFINITY
    {
        return None;
    }
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let used = kb_field(&status, "VmSize:").unwrap_or(0);
    Some((limit.rlim_cur.saturating_sub(used), limit.rlim_cur))
}

/// (MemAvailable, MemAvailable): nothing of it is this process's yet.
fn mem_available() -> Option<(u64, u64)> {
    let bytes = kb_field(
        &std::fs::read_to_string("/proc/meminfo").ok()?,
        "MemAvailable:",
    )?;
    Some((bytes, bytes))
}

/// `Key:   1234 kB` as bytes.
fn kb_field(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find_map(|l| l.strip_prefix(key))?;
    let kb: u64 = line.trim().trim_end_matches("kB").trim().parse().ok()?;
    Some(kb * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_never_read_as_zero() {
        assert_eq!(size(3_221_225_472), "3.22 GB");
        assert_eq!(size(153_200_000), "153.2 MB");
        assert_eq!(size(12_345), "12.3 kB");
        assert_eq!(size(512), "512 bytes");
    }

    #[test]
    fn vectors_grow_by_doubling_and_keep_their_elements() {
        let mut v: Vec<u64> = vec![1, 2, 3];
        v.shrink_to_fit();
        grow(&mut v, 1, || "a test".into()).unwrap();
        assert!(v.capacity() >= 16);
        assert_eq!(v, [1, 2, 3]);
    }
}

//! A render's image buffers measured against the memory this process may
//! still take, before the render starts: a hard limit (the address-space
//! or data `ulimit`, the cgroup's `memory.max`) that leaves too little, or
//! more than the machine's memory and swap in all, is an error; more than
//! is available now is a warning (the kernel may still find it). Without this, an allocation
//! that fails mid-render aborts the process with the runtime's one-line
//! "memory allocation of N bytes failed" and exit status 134. The buffers
//! are every one alive at the render's peak ([`RenderMemory`]); against
//! the address-space limit (`ulimit -v`) the threads' stacks and malloc
//! arenas count too, which take address space they hardly use.
//!
//! Linux only (read from `/proc` and `/sys/fs/cgroup`); elsewhere nothing
//! is checked.

use anyhow::{Result, anyhow};
use prism_geometry::glam::Vec3;
use std::mem::size_of;

/// Bytes of a linear colour: a pixel of `prism_shade::Image`, of the
/// alpha render's premultiplied colour and of its per-row copy.
const COLOUR: u64 = size_of::<Vec3>() as u64;
/// Bytes of a float: an alpha value, a channel of an AOV pass.
const FLOAT: u64 = size_of::<f32>() as u64;
/// Bytes per pixel of adaptive supersampling's base pass: its sums (a
/// colour), the range of its samples (`[Vec3; 2]`), the means its
/// neighbour test compares (a colour) and the flag it sets (`bool`).
const ADAPTIVE: u64 = (2 * size_of::<Vec3>() + size_of::<[Vec3; 2]>() + size_of::<bool>()) as u64;
/// An upper bound on the bytes of one image row's sink of passes and
/// coverage (`prism_shade`'s `AovRow`, under 200 bytes), its list of pass
/// buffers (24 bytes a pass) and the allocator's header of each of its
/// buffers (16 bytes): 256 bytes, and 64 a pass.
const ROW_BASE: u64 = 256;
const ROW_PER_PASS: u64 = 64;
/// What the estimate does not itemise: the encoders' state (the deflate
/// compressor's tables, the EXR writer's offset table and tiles), buffered
/// writers, the thread pools' queues.
const MARGIN: u64 = 16 << 20;
/// The address space glibc's malloc reserves for a thread's arena
/// (`HEAP_MAX_SIZE`, 64 MiB on 64-bit systems), at the thread's first
/// allocation, though it uses little of it. Counted only against
/// `ulimit -v`: the other limits see only the pages used.
const ARENA: u64 = 64 << 20;
/// A new thread's stack beyond its size (`RUST_MIN_STACK`, else Rust's 2
/// MiB): its guard page and its signal stack.
const STACK_EXTRA: u64 = 16 << 10;

/// The image buffers of one render (the whole image, or the part
/// `--pixel-bounds` or `--tile` asks for), for [`RenderMemory::bytes`]. It
/// holds the most in one of two phases.
///
/// While it renders (`prism_shade`'s `render_pixels`, then
/// `render_passes`), [`RenderMemory::rendering`]: the beauty (a colour a
/// pixel); with passes or `--alpha`, one sink a row holding that row's
/// passes and, with alpha, its premultiplied colour and coverage; and,
/// as the rows are gathered into whole-image buffers, those buffers too
/// (reserved whole before the first row is copied and freed). Under
/// adaptive supersampling (no passes, no alpha) the base pass's buffers
/// ([`ADAPTIVE`] bytes a pixel, with a border of one pixel around a part)
/// stand beside the beauty instead.
///
/// While it writes, [`RenderMemory::writing`]: what the render hands over
/// ([`RenderMemory::held`]: the colour, alpha, passes), the rows' memory
/// (freed, but not given back: the rows are small allocations from the
/// main thread's heap, which glibc returns only from its top, and a
/// writer on a `--threads` pool allocates from its own arena; measured, a
/// 6000 × 1000 `--aov all` render still held the rows' 264 MB in `[heap]`
/// while its EXR was written), and the writers' own copies and encoder
/// buffers (`Plan::writer_bytes`), the most of the writers that run in turn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderMemory {
    /// Pixels a row.
    pub width: u64,
    /// Rows.
    pub rows: u64,
    /// Whether the background is transparent (`--alpha`).
    pub alpha: bool,
    /// The AOV passes (each once).
    pub passes: u64,
    /// The passes' floats a pixel in all.
    pub pass_channels: u64,
    /// Pixels of adaptive supersampling's base pass, where it runs.
    pub adaptive_base: Option<u64>,
    /// The writers' bytes besides the render's buffers (`Plan::writer_bytes`).
    pub writers: u64,
    /// Worker threads the render starts: the `--threads` pool of the
    /// render and that of its writers (without `--threads` the render
    /// runs on the global pool, which the scene's BVH build started, and
    /// the writers on this thread).
    pub threads: u64,
}

impl RenderMemory {
    fn pixels(&self) -> u64 {
        self.width.saturating_mul(self.rows)
    }

    /// Whether the render gathers rows' sinks (passes or coverage).
    fn has_rows(&self) -> bool {
        self.alpha || self.pass_channels > 0
    }

    /// The rows' sinks: their buffers (passes; with alpha a colour and a
    /// float) and their own bookkeeping.
    fn row_sinks(&self) -> u64 {
        if !self.has_rows() {
            return 0;
        }
        let per_pixel = self.pass_channels * FLOAT + if self.alpha { COLOUR + FLOAT } else { 0 };
        let per_row = ROW_BASE + ROW_PER_PASS * self.passes;
        self.pixels().saturating_mul(per_pixel).saturating_add(self.rows.saturating_mul(per_row))
    }

    /// What the render hands to the writers: the colour (premultiplied
    /// with alpha), the alpha, the passes.
    pub fn held(&self) -> u64 {
        let per_pixel = COLOUR + if self.alpha { FLOAT } else { 0 } + self.pass_channels * FLOAT;
        self.pixels().saturating_mul(per_pixel)
    }

    /// The bytes held at once while rendering.
    pub fn rendering(&self) -> u64 {
        let beauty = self.pixels().saturating_mul(COLOUR);
        // With alpha the held colour is the premultiplied one, gathered
        // beside the beauty; without, the beauty itself.
        let gathered =
            if self.has_rows() { self.held().saturating_sub(beauty * u64::from(!self.alpha)) } else { 0 };
        let adaptive = match self.adaptive_base {
            Some(base) if !self.has_rows() => base.saturating_mul(ADAPTIVE),
            _ => 0,
        };
        beauty.saturating_add(self.row_sinks()).saturating_add(gathered).saturating_add(adaptive)
    }

    /// The bytes held at once while writing.
    pub fn writing(&self) -> u64 {
        self.held().saturating_add(self.row_sinks()).saturating_add(self.writers)
    }

    /// The image buffers at the render's peak, and [`MARGIN`]; every limit
    /// is measured against this.
    pub fn bytes(&self) -> u64 {
        self.rendering().max(self.writing()).saturating_add(MARGIN)
    }

    /// What `ulimit -v` sees besides [`RenderMemory::bytes`]: the stacks
    /// and malloc arenas ([`ARENA`]) of the threads the render starts, and
    /// the arenas of `pending` threads already running that have not
    /// reserved theirs (`pending_arenas`).
    pub fn threads_address_space(&self, pending: u64) -> u64 {
        let stack = std::env::var("RUST_MIN_STACK").ok().and_then(|s| s.parse().ok()).unwrap_or(2 << 20);
        let started = self.threads.saturating_mul(stack + STACK_EXTRA + ARENA);
        started.saturating_add(pending.saturating_mul(ARENA))
    }
}

/// The threads of this process besides this one whose malloc arenas are
/// not reserved yet, as far as `/proc/self` tells: each thread reserves one
/// ([`ARENA`]) when it first allocates (or takes over one a thread that
/// ended left), which a thread started a moment ago (the Ctrl-C handler's,
/// the global pool's) may not have done when `VmSize` is read. The threads
/// running, less the arenas mapped: 64 MiB-aligned runs of anonymous
/// mappings of 64 MiB, read-write first (what is used) and then
/// inaccessible (the rest). An arena not found so counts again, never the
/// other way.
fn pending_arenas() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let running = status
        .lines()
        .find_map(|l| l.strip_prefix("Threads:"))
        .and_then(|n| n.trim().parse::<u64>().ok())
        .unwrap_or(1)
        .saturating_sub(1);
    let maps = std::fs::read_to_string("/proc/self/maps").unwrap_or_default();
    running.saturating_sub(arena_heaps(&maps))
}

/// The malloc arenas' heaps in `maps` (`/proc/self/maps`), as
/// [`pending_arenas`] describes them.
fn arena_heaps(maps: &str) -> u64 {
    // Anonymous mappings: (start, end, readable and writable).
    let anonymous: Vec<(u64, u64, bool)> = maps
        .lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            let [range, perms, _, _, inode] = f.as_slice() else { return None };
            if *inode != "0" {
                return None;
            }
            let (start, end) = range.split_once('-')?;
            let hex = |x: &str| u64::from_str_radix(x, 16).ok();
            Some((hex(start)?, hex(end)?, perms.starts_with("rw")))
        })
        .collect();
    let mut heaps = 0;
    for (i, &(start, _, rw)) in anonymous.iter().enumerate() {
        if !rw || start % ARENA != 0 {
            continue;
        }
        let mut at = start;
        for &(s, e, _) in &anonymous[i..] {
            if s != at || e > start + ARENA {
                break;
            }
            at = e;
        }
        heaps += u64::from(at == start + ARENA);
    }
    heaps
}

/// Refuses a render whose image buffers ([`RenderMemory::bytes`], and
/// under `ulimit -v` its threads' address space) exceed what a hard limit
/// leaves this process or the machine's memory and swap in all; returns a
/// warning where they exceed what is available now.
pub fn check(need: &RenderMemory, what: &str) -> Result<Option<String>> {
    let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
    let bytes = need.bytes();
    for (left, limit, name) in hard_limits() {
        let threads = if name == "ulimit -v" { need.threads_address_space(pending_arenas()) } else { 0 };
        if bytes.saturating_add(threads) > left {
            let threads = if threads > 0 {
                format!(
                    " and {:.1} GiB of address space for its threads' stacks and malloc arenas",
                    gib(threads)
                )
            } else {
                String::new()
            };
            return Err(anyhow!(
                "{what} needs about {:.1} GiB for its image buffers{threads}, and this process may take only {:.1} GiB more ({limit}); lower --width/--height or drop AOV passes",
                gib(bytes),
                gib(left)
            ));
        }
    }
    if let Some(total) = machine_total()
        && bytes > total
    {
        return Err(anyhow!(
            "{what} needs about {:.1} GiB for its image buffers, more than this machine's {:.1} GiB of memory and swap; lower --width/--height or drop AOV passes",
            gib(bytes),
            gib(total)
        ));
    }
    Ok(soft_available().filter(|&free| bytes > free).map(|free| {
        format!(
            "{what} needs about {:.1} GiB for its image buffers, more than the {:.1} GiB of memory and swap available now",
            gib(bytes),
            gib(free)
        )
    }))
}

/// The memory this process may still take in all: the least room a hard
/// limit leaves, or the machine's memory and swap, whichever is less; for
/// the scene's textures ([`prism_scene::Limits::memory`]).
pub fn room() -> Option<prism_scene::MemoryRoom> {
    let hard =
        hard_limits().into_iter().next().map(|(bytes, _, limit)| prism_scene::MemoryRoom { bytes, limit });
    let machine = machine_total()
        .map(|bytes| prism_scene::MemoryRoom { bytes, limit: "the machine's memory and swap" });
    [hard, machine].into_iter().flatten().min_by_key(|r| r.bytes)
}

/// The room each hard limit leaves, with the limit's description and its
/// name, the least room first.
fn hard_limits() -> Vec<(u64, String, &'static str)> {
    let status = std::fs::read_to_string("/proc/self/status").ok();
    let kib = |key: &str| status.as_deref().and_then(|s| field_kib(s, key));
    let limits = std::fs::read_to_string("/proc/self/limits").ok();
    let mut room: Vec<(u64, String, &'static str)> = Vec::new();
    if let Some(l) = limits.as_deref() {
        for (name, used, what) in
            [("Max address space", "VmSize:", "ulimit -v"), ("Max data size", "VmData:", "ulimit -d")]
        {
            if let (Some(limit), Some(used)) = (soft_limit(l, name), kib(used)) {
                room.push((
                    limit.saturating_sub(used.saturating_mul(1024)),
                    format!("{what}: {limit} bytes"),
                    what,
                ));
            }
        }
    }
    if let Some((max, current)) = cgroup_memory() {
        room.push((
            max.saturating_sub(current),
            format!("cgroup memory.max: {max} bytes"),
            "cgroup memory.max",
        ));
    }
    room.sort_by_key(|(left, ..)| *left);
    room
}

/// `MemTotal + SwapTotal` of `/proc/meminfo`, in bytes.
fn machine_total() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let total = field_kib(&info, "MemTotal:")?.saturating_add(field_kib(&info, "SwapTotal:").unwrap_or(0));
    Some(total.saturating_mul(1024))
}

/// `MemAvailable + SwapFree` of `/proc/meminfo`, in bytes.
fn soft_available() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let free = field_kib(&info, "MemAvailable:")?.saturating_add(field_kib(&info, "SwapFree:").unwrap_or(0));
    Some(free.saturating_mul(1024))
}

/// The value in kiB of the line `KEY   N kB` in `/proc`'s format.
fn field_kib(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    line[key.len()..].split_whitespace().next()?.parse().ok()
}

/// The soft limit of the row `name` of `/proc/self/limits`, in bytes;
/// `None` where it is "unlimited".
fn soft_limit(limits: &str, name: &str) -> Option<u64> {
    let line = limits.lines().find(|l| l.starts_with(name))?;
    line[name.len()..].split_whitespace().next()?.parse().ok()
}

/// This process's cgroup (v2) `memory.max` and `memory.current`, where
/// the maximum is set.
fn cgroup_memory() -> Option<(u64, u64)> {
    let cgroup = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let path = cgroup.lines().find_map(|l| l.strip_prefix("0::"))?;
    let dir = std::path::Path::new("/sys/fs/cgroup").join(path.trim_start_matches('/'));
    let read = |f: &str| std::fs::read_to_string(dir.join(f)).ok()?.trim().parse::<u64>().ok();
    Some((read("memory.max")?, read("memory.current")?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn proc_fields_and_limits_are_read() {
        let status = "Name:\tprism\nVmSize:\t  3896 kB\nVmData:\t   428 kB\n";
        assert_eq!(field_kib(status, "VmSize:"), Some(3896));
        assert_eq!(field_kib(status, "VmData:"), Some(428));
        assert_eq!(field_kib(status, "VmRSS:"), None);
        let limits = "Limit                     Soft Limit           Hard Limit           Units     \n\
                      Max data size             unlimited            unlimited            bytes     \n\
                      Max address space         2048000000           unlimited            bytes     \n";
        assert_eq!(soft_limit(limits, "Max address space"), Some(2_048_000_000));
        assert_eq!(soft_limit(limits, "Max data size"), None);
    }

    /// A render of `aovs` (with `alpha`) by the same calls as
    /// `render_to`, and the bytes of the buffers it returns: the beauty
    /// image of a plain render of the same size, and what the writers
    /// are handed (colour, alpha, passes), from the buffers' own lengths
    /// and element types.
    fn real_buffers(width: u32, height: u32, alpha: bool, aovs: &[prism_shade::Aov]) -> (u64, u64) {
        use prism_shade::{RenderHooks, render, render_with_alpha, render_with_aovs};
        let text = "[render]\nwidth = 8\nheight = 8\n[camera]\nposition = [0, 1, 5]\nlook_at = [0, 1, 0]\n\
                    [[lights]]\nposition = [3, 5, 4]\n[[objects]]\ntype = \"sphere\"\ncenter = [0, 1, 0]\nradius = 1\n";
        let dir = std::path::Path::new(".");
        let loaded = prism_scene::parse_scene_str(text, dir, std::path::Path::new("s.toml")).unwrap();
        let settings = loaded.settings.with_size(width, height).unwrap();
        let bytes = |v: usize, t: usize| (v * t) as u64;
        let vec3 = size_of::<Vec3>();
        let (beauty, _) = render(&loaded.scene, &settings, RenderHooks::default());
        let beauty = bytes(beauty.pixels.capacity(), vec3);
        let passes = |p: &prism_shade::AovImages| -> u64 {
            p.passes.iter().map(|p| bytes(p.data.capacity(), size_of::<f32>())).sum()
        };
        let held = if alpha {
            let (rgba, p, _) = render_with_alpha(&loaded.scene, &settings, aovs, RenderHooks::default());
            bytes(rgba.color.pixels.capacity(), vec3)
                + bytes(rgba.alpha.capacity(), size_of::<f32>())
                + passes(&p)
        } else if aovs.is_empty() {
            beauty
        } else {
            let (image, p, _) = render_with_aovs(&loaded.scene, &settings, aovs, RenderHooks::default());
            bytes(image.pixels.capacity(), vec3) + passes(&p)
        };
        (beauty, held)
    }

    #[test]
    fn malloc_arenas_are_found_in_the_maps() {
        // A prism render's anonymous mappings: four arenas (two of them
        // side by side), a buffer, thread stacks with their guard pages.
        let maps = "55ac85e71000-55ac85e73000 rw-p 00000000 00:00 0\n\
                    55ac86e71000-55ac86e93000 rw-p 00000000 00:00 0    [heap]\n\
                    7f1690000000-7f1690021000 rw-p 00000000 00:00 0\n\
                    7f1690021000-7f1694000000 ---p 00000000 00:00 0\n\
                    7f1694000000-7f1694021000 rw-p 00000000 00:00 0\n\
                    7f1694021000-7f1698000000 ---p 00000000 00:00 0\n\
                    7f169ed57000-7f16b0000000 rw-p 00000000 00:00 0\n\
                    7f16b0000000-7f16b0021000 rw-p 00000000 00:00 0\n\
                    7f16b0021000-7f16b4000000 ---p 00000000 00:00 0\n\
                    7f16b56d7000-7f16b56d8000 ---p 00000000 00:00 0\n\
                    7f16b56d8000-7f16b58d8000 rw-p 00000000 00:00 0\n\
                    7f16c0000000-7f16c4000000 r--p 00000000 08:01 1234 /lib/x.so\n\
                    7f16c4000000-7f16c4021000 rw-p 00000000 00:00 0\n\
                    7f16c4021000-7f16c9000000 ---p 00000000 00:00 0\n";
        // Not the file, nor the run that goes past 64 MiB.
        assert_eq!(arena_heaps(maps), 3);
        assert_eq!(arena_heaps(""), 0);
    }

    #[test]
    fn the_estimate_holds_every_buffer_alive_at_once() {
        use prism_shade::Aov;
        let (w, h) = (24, 10);
        let modes: [(bool, &[Aov]); 5] = [
            (false, &[]),
            (true, &[]),
            (false, &[Aov::Depth, Aov::Normal]),
            (false, &Aov::ALL),
            (true, &Aov::ALL),
        ];
        for (alpha, aovs) in modes {
            let writers = 1000;
            let need = RenderMemory {
                width: w.into(),
                rows: h.into(),
                alpha,
                passes: aovs.len() as u64,
                pass_channels: aovs.iter().map(|a| a.channels() as u64).sum(),
                adaptive_base: None,
                writers,
                threads: 0,
            };
            let (beauty, held) = real_buffers(w, h, alpha, aovs);
            let mode = format!("alpha {alpha}, passes {aovs:?}");
            // What the render hands the writers, to the byte.
            assert_eq!(need.held(), held, "{mode}");
            // While rendering: the beauty, each row's sink of passes (and
            // coverage), and the whole-image buffers they are gathered into
            // (with alpha the handed colour is the coverage's, beside the
            // beauty). An estimate of the handed buffers and the files'
            // copies alone (as before) missed the first two.
            let gathered = if alpha { held } else { held - beauty };
            assert!(need.rendering() >= beauty + 2 * gathered, "{mode}");
            // While writing: the handed buffers, the rows' memory (freed
            // into a heap that does not shrink), the writers' copies.
            assert!(need.writing() >= held + gathered + writers, "{mode}");
            assert!(need.bytes() >= need.rendering().max(need.writing()), "{mode}");
        }
        // Adaptive supersampling's base pass beside the beauty: sums,
        // ranges, means, flags.
        let base = RenderMemory {
            width: 100,
            rows: 100,
            alpha: false,
            passes: 0,
            pass_channels: 0,
            adaptive_base: Some(102 * 102),
            writers: 0,
            threads: 2,
        };
        let per_pixel = 2 * size_of::<Vec3>() + size_of::<[Vec3; 2]>() + size_of::<bool>();
        assert!(base.rendering() >= 100 * 100 * 12 + 102 * 102 * per_pixel as u64);
        // Two new threads' stacks and arenas, and one pending arena.
        assert!(base.threads_address_space(1) >= 2 * ((2 << 20) + ARENA) + ARENA);
        // Nothing is refused that fits; sizes past u64 saturate.
        assert!(
            check(&RenderMemory { width: 1, rows: 1, writers: 0, threads: 0, ..base }, "a render").is_ok()
        );
        let huge = RenderMemory { width: u64::MAX, rows: u64::MAX, alpha: true, ..base };
        assert_eq!(huge.bytes(), u64::MAX);
    }
}

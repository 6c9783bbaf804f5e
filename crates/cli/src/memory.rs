//! A render's image buffers measured against the memory this process may
//! still take, before the render starts: a hard limit (the address-space
//! or data `ulimit`, the cgroup's `memory.max`) that leaves too little, or
//! more than the machine's memory and swap in all, is an error; more than
//! is available now is a warning (the kernel may still find it). Without this, an allocation
//! that fails mid-render aborts the process with the runtime's one-line
//! "memory allocation of N bytes failed" and exit status 134.
//!
//! Linux only (read from `/proc` and `/sys/fs/cgroup`); elsewhere nothing
//! is checked.

use anyhow::{Result, anyhow};

/// Bytes a render of `pixels` pixels holds at once, besides the scene:
/// the linear colour (three `f32`s), its alpha when kept, the AOV passes
/// (`pass_channels` floats in all), and the encoded output
/// (`encoded_per_pixel` bytes a pixel). A lower bound: the render's own
/// bookkeeping comes on top.
pub fn image_bytes(pixels: u64, alpha: bool, pass_channels: u64, encoded_per_pixel: u64) -> u64 {
    let floats = 3 + u64::from(alpha) + pass_channels;
    pixels.saturating_mul(floats * 4 + encoded_per_pixel)
}

/// Refuses a render whose image buffers (`needed` bytes, [`image_bytes`])
/// exceed what a hard limit leaves this process or the machine's memory
/// and swap in all; returns a warning where they exceed what is available
/// now.
pub fn check(needed: u64, what: &str) -> Result<Option<String>> {
    let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
    if let Some((left, limit, _)) = hard_headroom()
        && needed > left
    {
        return Err(anyhow!(
            "{what} needs about {:.1} GiB for its image buffers, and this process may take only {:.1} GiB more ({limit}); lower --width/--height or drop AOV passes",
            gib(needed),
            gib(left)
        ));
    }
    if let Some(total) = machine_total()
        && needed > total
    {
        return Err(anyhow!(
            "{what} needs about {:.1} GiB for its image buffers, more than this machine's {:.1} GiB of memory and swap; lower --width/--height or drop AOV passes",
            gib(needed),
            gib(total)
        ));
    }
    Ok(soft_available().filter(|&free| needed > free).map(|free| {
        format!(
            "{what} needs about {:.1} GiB for its image buffers, more than the {:.1} GiB of memory and swap available now",
            gib(needed),
            gib(free)
        )
    }))
}

/// The memory this process may still take in all: the least room a hard
/// limit leaves, or the machine's memory and swap, whichever is less; for
/// the scene's textures ([`prism_scene::Limits::memory`]).
pub fn room() -> Option<prism_scene::MemoryRoom> {
    let hard = hard_headroom().map(|(bytes, _, limit)| prism_scene::MemoryRoom { bytes, limit });
    let machine = machine_total()
        .map(|bytes| prism_scene::MemoryRoom { bytes, limit: "the machine's memory and swap" });
    [hard, machine].into_iter().flatten().min_by_key(|r| r.bytes)
}

/// The least room any hard limit leaves, with the limit's description and
/// its name.
fn hard_headroom() -> Option<(u64, String, &'static str)> {
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
    room.into_iter().min_by_key(|(left, ..)| *left)
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

    #[test]
    fn the_image_bytes_count_every_buffer() {
        // 100 × 100 pixels: RGB floats (12), alpha (4), two passes of three
        // channels (24), and a 3-byte PNG pixel.
        assert_eq!(image_bytes(10_000, true, 6, 3), 10_000 * 43);
        assert_eq!(image_bytes(u64::MAX, false, 0, 3), u64::MAX);
        // Nothing is refused that fits.
        assert!(check(1, "a render").is_ok());
    }
}

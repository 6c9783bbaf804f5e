//! `prism render --stats-json FILE`: the render's figures as one JSON
//! object for scripts: wall time per phase, rays per kind, the BVH's size
//! and the process's peak memory. Keys are listed in the README.

use prism_scene::LoadedScene;
use prism_shade::RenderStats;
use std::path::Path;

/// Wall-clock seconds of each phase of `prism render`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Phases {
    /// Reading and building the scene (the BVH build included).
    pub load: f64,
    /// The render itself (beauty and AOV passes).
    pub render: f64,
    /// Writing the image and the AOV files.
    pub write: f64,
}

/// The peak resident memory of this process in bytes (`VmHWM` of
/// `/proc/self/status`), or `None` where that is not available (not
/// Linux).
#[must_use]
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    vm_hwm(&status)
}

/// The `VmHWM:` line of a `/proc/PID/status` text, in bytes.
fn vm_hwm(status: &str) -> Option<u64> {
    let line = status.lines().find_map(|l| l.strip_prefix("VmHWM:"))?;
    let mut words = line.split_whitespace();
    let n: u64 = words.next()?.parse().ok()?;
    match words.next() {
        Some("kB") => n.checked_mul(1024),
        _ => None,
    }
}

/// The statistics object written by `--stats-json`.
pub fn to_json(
    loaded: &LoadedScene,
    scene: &Path,
    outputs: &[&Path],
    phases: Phases,
    stats: &RenderStats,
) -> serde_json::Value {
    let (w, h) = loaded.settings.camera.size();
    let bvh = loaded.scene.accel.stats();
    let total = phases.load + phases.render + phases.write;
    serde_json::json!({
        "scene": prism_scene::scene_name(scene),
        "outputs": outputs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        "image": {
            "width": w,
            "height": h,
            "spp": loaded.settings.spp,
            "filter": loaded.settings.antialias.filter.name(),
            "adaptive": loaded.settings.antialias.adaptive.map(crate::info::num),
        },
        "threads": loaded.settings.threads.unwrap_or_else(rayon_threads),
        "seconds": {
            "load": phases.load,
            "bvh_build": bvh.build_seconds,
            "render": phases.render,
            "write": phases.write,
            "total": total,
        },
        "rays": {
            "total": stats.rays,
            "camera": stats.camera_rays,
            "shadow": stats.shadow_rays,
            "secondary": stats.secondary_rays(),
            "aov": stats.aov_rays,
            "packet": stats.packet_rays,
        },
        "mrays_per_second": if phases.render > 0.0 { stats.rays as f64 / 1e6 / phases.render } else { 0.0 },
        "nonfinite_samples": stats.nonfinite_samples,
        "bvh": {
            "nodes": bvh.bvh_nodes,
            "bytes": bvh.bvh_bytes,
            "stored_triangles": bvh.stored_triangles,
            "instanced_triangles": bvh.instanced_triangles,
            "unbounded_objects": bvh.unbounded_objects,
        },
        "peak_memory_bytes": peak_memory_bytes(),
    })
}

/// The number of threads a render with `threads = None` uses (every core).
fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, usize::from)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vm_hwm_is_read_in_bytes() {
        let status = "Name:\tprism\nVmPeak:\t  20000 kB\nVmHWM:\t    1234 kB\nVmRSS:\t 1000 kB\n";
        assert_eq!(vm_hwm(status), Some(1234 * 1024));
        assert_eq!(vm_hwm("VmRSS: 5 kB\n"), None);
        assert_eq!(vm_hwm("VmHWM: lots\n"), None);
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn this_process_has_a_peak() {
        let peak = peak_memory_bytes().unwrap();
        assert!(peak > 1 << 20, "{peak}");
    }
}

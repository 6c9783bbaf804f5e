//! The environment variables that change how prism traces
//! (`PRISM_BVH_KERNEL`, `PRISM_PACKETS`, `PRISM_BVH_BLAS`): the libraries
//! read them and quietly fall back on a value they do not know, so the
//! commands that trace check them first and warn.

use prism_bvh::{BlasKind, Kernel};

/// A warning for each of the variables set to a value that will be
/// ignored (or, for a kernel, that this CPU cannot run).
pub fn warnings() -> Vec<String> {
    let var = |name: &str| std::env::var(name).ok();
    let mut out = Vec::new();
    if let Some(k) = var("PRISM_BVH_KERNEL")
        && std::env::var_os("PRISM_BVH_NO_SIMD").is_none()
    {
        let used = Kernel::detect().name();
        match Kernel::ALL.into_iter().find(|c| c.name() == k) {
            None => {
                let names: Vec<&str> = Kernel::ALL.iter().map(|c| c.name()).collect();
                out.push(format!(
                    "PRISM_BVH_KERNEL={k:?} is not a kernel ({}); using {used}",
                    names.join(", ")
                ));
            }
            Some(c) if !c.supported() => {
                out.push(format!("PRISM_BVH_KERNEL={k}: this CPU cannot run it; using {used}"));
            }
            Some(_) => {}
        }
    }
    if let Some(p) = var("PRISM_PACKETS")
        && !prism_shade::PACKET_MODES.contains(&p.as_str())
    {
        out.push(format!(
            "PRISM_PACKETS={p:?} is not one of {}; every ray is traced alone, as with 0",
            prism_shade::PACKET_MODES.join(", ")
        ));
    }
    if let Some(b) = var("PRISM_BVH_BLAS")
        && BlasKind::from_env().is_none()
    {
        let names: Vec<&str> = BlasKind::ALL.iter().map(|c| c.name()).collect();
        out.push(format!("PRISM_BVH_BLAS={b:?} is not a layout ({}); using the default", names.join(", ")));
    }
    out
}

//! Turntables: `prism render --frames N --orbit DEGREES [--frame I |
//! --frame-from-env]`. Frame `I` of `N` views the scene from the camera
//! turned about the vertical (+Y) axis through its look-at point by
//! `I · DEGREES / N` degrees (counter-clockwise seen from above), so that
//! `--orbit 360` loops without repeating a frame; it is written to
//! `OUT.####.png` (the output's stem, the zero-padded frame number, its
//! extension).

use crate::tile::task_index;
use anyhow::{Result, anyhow, bail};
use clap::Args;
use prism_geometry::glam::{Quat, Vec3};
use prism_shade::{Camera, RenderSettings};
use std::path::{Path, PathBuf};

/// The turntable flags of `prism render`.
#[derive(Args, Clone, Debug, Default)]
pub struct FrameArgs {
    /// Render an N-frame turntable to OUT.####.png: the camera orbits its look-at point
    /// about +Y by --orbit degrees over the sequence.
    #[arg(long, value_name = "N", conflicts_with_all = ["pixel_bounds", "tile", "tile_from_env"])]
    pub frames: Option<u32>,
    /// Degrees the camera turns over the --frames sequence [default: 360].
    #[arg(long, value_name = "DEGREES", requires = "frames", allow_hyphen_values = true)]
    pub orbit: Option<f32>,
    /// Render only frame I (0-based) of the --frames sequence.
    #[arg(long, value_name = "I", requires = "frames", conflicts_with = "frame_from_env")]
    pub frame: Option<u32>,
    /// Render only frame I, with I from $SLURM_ARRAY_TASK_ID or else $JOB_COMPLETION_INDEX.
    #[arg(long, requires = "frames")]
    pub frame_from_env: bool,
}

/// Refuses an `--orbit` that is not a finite number of degrees (one past
/// f32's range reads as infinite: it is not named as "inf").
pub fn check_orbit(orbit: f32) -> Result<()> {
    if orbit.is_nan() {
        bail!("--orbit NaN: the angle must be a finite number of degrees");
    }
    if orbit.is_infinite() {
        bail!("--orbit: the angle must be a finite number of degrees, at most about 3.4e38");
    }
    Ok(())
}

/// The camera of frame `index` of `count` turning `orbit` degrees in all.
///
/// # Errors
/// If the turned camera is invalid (it cannot be, for a valid `camera`
/// and finite `orbit`).
pub fn orbit_camera(camera: &Camera, orbit: f32, index: u32, count: u32) -> Result<Camera> {
    // Within a turn first, in f64: a large orbit's f32 radians are coarse.
    let angle = ((f64::from(orbit) * f64::from(index) / f64::from(count.max(1))) % 360.0).to_radians() as f32;
    let turn = Quat::from_axis_angle(Vec3::Y, angle);
    let centre = camera.look_at();
    // Projection and lens travel with the camera: frame 0 is the scene's own view.
    Ok(camera.moved(centre + turn * (camera.position() - centre), centre, turn * camera.up())?)
}

/// `OUT.####.ext`: `output` with the frame number (zero-padded to four
/// digits, more if `count` needs them) before its extension.
pub fn frame_path(output: &Path, index: u32, count: u32) -> PathBuf {
    let digits = count.saturating_sub(1).to_string().len().max(4);
    let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let ext = output.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    output.with_file_name(format!("{stem}.{index:0digits$}{ext}"))
}

/// The frames of a `count`-frame turntable written to `output` whose
/// names exist already (an input of the render, a folder, an earlier
/// run's frame), found by one listing of the output's folder whatever
/// `count` is: the names a check must see before any frame is rendered
/// or submitted.
pub fn existing_frames(output: &Path, count: u32) -> Vec<PathBuf> {
    let dir = output.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    let digits = count.saturating_sub(1).to_string().len().max(4);
    let stem = output.file_stem().map(|s| format!("{}.", s.to_string_lossy())).unwrap_or_default();
    let ext = output.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    let mut found: Vec<PathBuf> = entries
        .filter_map(|e| {
            let name = e.ok()?.file_name().into_string().ok()?;
            let number = name.strip_prefix(&stem)?.strip_suffix(&ext)?;
            let index: u64 = number.parse().ok().filter(|_| number.len() == digits)?;
            (number.bytes().all(|b| b.is_ascii_digit()) && index < u64::from(count))
                .then(|| output.with_file_name(&name))
        })
        .collect();
    found.sort();
    found
}

/// The renders to make: `(settings, output)` for each frame asked for, or
/// the one render of `settings` to `output` without `--frames`.
///
/// # Errors
/// `--frames 0`, a non-finite `--orbit`, `--frame I` with `I ≥ N`, or no
/// index in the environment, naming the flag.
pub fn plan(
    args: &FrameArgs,
    settings: &RenderSettings,
    output: &Path,
) -> Result<Vec<(RenderSettings, PathBuf)>> {
    let Some(count) = args.frames else {
        return Ok(vec![(settings.clone(), output.to_path_buf())]);
    };
    if count == 0 {
        bail!("--frames 0: a turntable needs at least 1 frame");
    }
    let orbit = args.orbit.unwrap_or(360.0);
    check_orbit(orbit)?;
    let only = match (args.frame, args.frame_from_env) {
        (Some(i), _) => Some(("--frame", i)),
        (None, true) => Some(("--frame-from-env", task_index("--frame-from-env")?)),
        (None, false) => None,
    };
    let frames: Vec<u32> = match only {
        Some((flag, i)) if i >= count => {
            bail!("{flag}: frame {i} does not exist; --frames {count} numbers them 0 to {}", count - 1)
        }
        Some((_, i)) => vec![i],
        None => (0..count).collect(),
    };
    frames
        .into_iter()
        .map(|i| {
            let camera =
                orbit_camera(&settings.camera, orbit, i, count).map_err(|e| anyhow!("--orbit: {e}"))?;
            Ok((RenderSettings { camera, ..settings.clone() }, frame_path(output, i, count)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_orbit_the_look_at_point_about_y() {
        let cam =
            Camera::new(Vec3::new(0.0, 2.0, 5.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 40.0, 8, 6).unwrap();
        // A quarter turn: +Z goes to +X (counter-clockwise seen from above).
        let q = orbit_camera(&cam, 360.0, 1, 4).unwrap();
        assert!((q.position() - Vec3::new(5.0, 2.0, 0.0)).length() < 1e-5, "{:?}", q.position());
        assert_eq!((q.look_at(), q.size(), q.vfov_deg()), (cam.look_at(), (8, 6), 40.0));
        // Distance to the look-at point and height are kept on every frame; frame 0 is the camera.
        for i in 0..7 {
            let c = orbit_camera(&cam, 90.0, i, 7).unwrap();
            assert!(
                ((c.position() - c.look_at()).length() - (cam.position() - cam.look_at()).length()).abs()
                    < 1e-5
            );
            assert!((c.position().y - 2.0).abs() < 1e-6);
        }
        assert_eq!(orbit_camera(&cam, 360.0, 0, 3).unwrap(), cam);
        // 1e9° is 280°: reduced in f64 before its f32 radians, which are
        // spaced 2 apart at 1.7e7.
        let (big, small) = (orbit_camera(&cam, 1e9, 1, 1).unwrap(), orbit_camera(&cam, 280.0, 1, 1).unwrap());
        assert!((big.position() - small.position()).length() < 1e-5, "{:?}", big.position());
    }

    #[test]
    fn frame_names_and_plans() {
        assert_eq!(frame_path(Path::new("out/t.png"), 7, 3), Path::new("out/t.0007.png"));
        assert_eq!(frame_path(Path::new("t.exr"), 12, 20_000), Path::new("t.00012.exr"));
    }

    #[test]
    fn existing_frames_are_the_sequences_names_found_in_its_folder() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("t.png");
        for name in [
            "t.0000.png",
            "t.0002.png",
            "t.0003.png",
            "t.002.png",
            "t.00001.png",
            "t.0001.exr",
            "u.0001.png",
            "t.000a.png",
        ] {
            std::fs::write(dir.path().join(name), b"").unwrap();
        }
        std::fs::create_dir(dir.path().join("t.0001.png")).unwrap();
        let found = existing_frames(&out, 3);
        let names: Vec<_> =
            found.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
        assert_eq!(names, ["t.0000.png", "t.0001.png", "t.0002.png"]);
        assert!(found.iter().all(|p| p.parent() == Some(dir.path())));
        // Each found name is the frame's own path.
        assert_eq!(found[1], frame_path(&out, 1, 3));
        assert!(existing_frames(&dir.path().join("none/t.png"), 3).is_empty());
        assert_eq!(existing_frames(&out, u32::MAX).len(), 0, "ten digits for 2^32 frames");
        let cam = Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0, 2, 2).unwrap();
        let settings = RenderSettings {
            camera: cam,
            fog: false,
            spp: 1,
            max_depth: 1,
            min_contribution: 0.0,
            threads: None,
            antialias: prism_shade::Antialias::default(),
        };
        let args = |frames, frame| FrameArgs { frames, orbit: Some(90.0), frame, frame_from_env: false };
        assert_eq!(plan(&args(None, None), &settings, Path::new("a.png")).unwrap().len(), 1);
        let all = plan(&args(Some(3), None), &settings, Path::new("a.png")).unwrap();
        assert_eq!(
            all.iter().map(|(_, p)| p.clone()).collect::<Vec<_>>(),
            ["a.0000.png", "a.0001.png", "a.0002.png"].map(PathBuf::from)
        );
        let one = plan(&args(Some(3), Some(2)), &settings, Path::new("a.png")).unwrap();
        assert_eq!(one, vec![all[2].clone()]);
        let e = plan(&args(Some(3), Some(3)), &settings, Path::new("a.png")).unwrap_err().to_string();
        assert_eq!(e, "--frame: frame 3 does not exist; --frames 3 numbers them 0 to 2");
        assert!(
            plan(&args(Some(0), None), &settings, Path::new("a.png"))
                .unwrap_err()
                .to_string()
                .starts_with("--frames 0")
        );
    }

    #[test]
    fn frame_zero_is_the_scenes_own_camera_lens_and_projection_included() {
        use prism_shade::Projection;
        let cam = Camera::new(Vec3::new(0.0, 2.0, 6.0), Vec3::ZERO, Vec3::Y, 40.0, 8, 6)
            .unwrap()
            .with_projection(Projection::Orthographic)
            .with_lens(0.2, 5.0)
            .unwrap();
        let first = orbit_camera(&cam, 90.0, 0, 4).unwrap();
        for (x, y) in [(0.5, 0.5), (3.7, 2.2), (7.5, 5.5)] {
            assert_eq!(first.ray(x, y), cam.ray(x, y));
        }
        let turned = orbit_camera(&cam, 90.0, 1, 4).unwrap();
        assert_eq!((turned.projection(), turned.aperture()), (Projection::Orthographic, 0.2));
    }
}

//! Rays traced in packets (`PRISM_PACKETS`) give the very same image as
//! rays traced one by one, and the statistics say which were packed.

mod common;

use common::{prism_cmd, text};
use std::fs;
use std::path::Path;

/// Mesh instances (packets are used only in scenes with them), an opaque and a glass material
/// (`gem_material` is the gem's material line: empty for its MTL's glass), an area light of 16
/// samples and a point light.
fn scene(gem_material: &str) -> String {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    let torus = assets.join("torus.obj");
    let gem = assets.join("gem.obj");
    format!(
        r#"[render]
width = 64
height = 40
spp = 3
background = [0.4, 0.5, 0.7]

[camera]
position = [0, 2.5, 6]
look_at = [0, 0.6, 0]
fov = 45

[[lights]]
type = "quad"
corner = [-2, 5, 1]
edge_u = [1.5, 0, 0]
edge_v = [0, 0, 1.5]
samples = 16
adaptive = {adaptive}
intensity = 4

[[lights]]
position = [4, 6, 3]
intensity = 0.4

[materials.floor]
texture = {{ type = "checker", a = [0.8, 0.8, 0.8], b = [0.3, 0.3, 0.3], size = 0.5 }}

[materials.red]
color = [0.8, 0.2, 0.1]
specular = 0.4

[[objects]]
type = "plane"
material = "floor"

[[objects]]
type = "mesh"
path = "{torus}"
material = "red"
transform = [{{ rotate_x = 30 }}, {{ translate = [-0.8, 0.7, 0] }}]

[[objects]]
type = "mesh"
path = "{gem}"
{gem_material}
transform = [{{ scale = 0.7 }}, {{ translate = [1.2, 0.7, 0.5] }}]
"#,
        torus = torus.display(),
        gem = gem.display(),
        adaptive = "{adaptive}",
    )
}

/// Renders `scene` with `PRISM_PACKETS=choice` (or unset); returns the
/// bytes of the float EXR image (every bit of every pixel) and the
/// statistics.
fn render(dir: &Path, choice: Option<&str>, name: &str) -> (Vec<u8>, serde_json::Value) {
    let mut cmd = prism_cmd(dir);
    cmd.env_remove("PRISM_PACKETS");
    if let Some(c) = choice {
        cmd.env("PRISM_PACKETS", c);
    }
    let exr = format!("{name}.exr");
    let json = format!("{name}.json");
    let out = cmd.args(["render", "s.toml", "-q", "-o", &exr, "--stats-json", &json]).output().unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stats = serde_json::from_slice(&fs::read(dir.join(&json)).unwrap()).unwrap();
    (fs::read(dir.join(&exr)).unwrap(), stats)
}

#[test]
fn packets_change_no_pixel() {
    for adaptive in ["false", "true"] {
        let dir = tempfile::tempdir().unwrap();
        let text = scene("").replace("{adaptive}", adaptive);
        fs::write(dir.path().join("s.toml"), text).unwrap();
        let (alone, s0) = render(dir.path(), Some("0"), "alone");
        let (default, sd) = render(dir.path(), None, "default");
        let (camera_only, s1) = render(dir.path(), Some("camera"), "camera");
        let (all, s2) = render(dir.path(), Some("all"), "all");
        assert!(alone == default, "adaptive = {adaptive}: the default changed the image");
        assert!(alone == camera_only, "adaptive = {adaptive}: camera packets changed the image");
        assert!(alone == all, "adaptive = {adaptive}: shadow packets changed the image");
        let packed = |s: &serde_json::Value| s["rays"]["packet"].as_u64().unwrap();
        let camera = s0["rays"]["camera"].as_u64().unwrap();
        assert_eq!(camera, 64 * 40 * 3);
        assert_eq!(packed(&s0), 0, "PRISM_PACKETS=0 packs nothing");
        assert_eq!(packed(&sd), camera, "by default: the camera rays, all of them");
        assert_eq!(packed(&s1), camera, "camera: the camera rays, all of them");
        assert!(packed(&s2) > camera, "all: shadow rays too ({})", packed(&s2));
        for s in [&sd, &s1, &s2] {
            assert_eq!(s["rays"]["camera"], s0["rays"]["camera"]);
        }
        // Without the light's probes (which a packet traces all four of,
        // where one by one stops at the first that differs), the same
        // shadow rays: one occluded by the glass gem and traced again for
        // its crossings counts once.
        if adaptive == "false" {
            for s in [&sd, &s1, &s2] {
                assert_eq!(s["rays"]["shadow"], s0["rays"]["shadow"], "shadow rays");
                assert_eq!(s["rays"]["total"], s0["rays"]["total"], "all rays");
            }
        }
    }
}

/// In a scene with nothing see-through, the default packs the camera hits'
/// shadow rays toward the point, spot and directional lights too (the
/// spot's cone leaves part of the view unlit): the same image, and the same
/// count of shadow rays as one by one. Ten lights: the two after the eighth
/// are traced one by one.
#[test]
fn camera_hit_shadow_packets_change_no_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let lights = r#"
[[lights]]
type = "spot"
position = [0.5, 4, 1]
direction = [-0.2, -1, -0.1]
outer_angle = 25
intensity = 0.5

[[lights]]
type = "directional"
direction = [1, -2, -1]
intensity = 0.3
"#
    .to_owned()
        + &(0..6)
            .map(|k| format!("\n[[lights]]\nposition = [{}, 3, {}]\nintensity = 0.05\n", k - 3, 2 - k))
            .collect::<String>();
    let text = scene(r#"material = "red""#).replace("{adaptive}", "false") + &lights;
    fs::write(dir.path().join("s.toml"), text).unwrap();
    let (alone, s0) = render(dir.path(), Some("0"), "alone");
    let (default, sd) = render(dir.path(), None, "default");
    let (all, s2) = render(dir.path(), Some("all"), "all");
    assert!(alone == default, "the default's shadow packets changed the image");
    assert!(alone == all, "all packets changed the image");
    let rays = |s: &serde_json::Value, kind: &str| s["rays"][kind].as_u64().unwrap();
    let camera = rays(&s0, "camera");
    // Camera rays, then at most one shadow ray per camera hit toward each
    // one-sample light among the first eight (the first is the area light).
    let packed = rays(&sd, "packet");
    assert!(packed > 2 * camera && packed <= 8 * camera, "{packed} packed of {camera} camera rays");
    assert!(rays(&s2, "packet") > packed, "all: the area light's shadow rays too");
    for kind in ["camera", "shadow", "total"] {
        assert_eq!(rays(&sd, kind), rays(&s0, kind), "{kind} rays");
    }
}

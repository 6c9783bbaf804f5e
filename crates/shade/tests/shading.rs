//! Numerical checks of the Whitted integrator against closed-form answers.

mod common;
use common::*;
use prism_geometry::glam::Vec3;
use prism_geometry::{Cuboid, Cylinder, Disk, Plane, Sphere, Transform};
use prism_shade::{Material, PointLight, Texture};

fn sphere(c: Vec3, r: f32) -> prism_geometry::Shape {
    Sphere::new(c, r).expect("valid sphere").into()
}

fn plane(p: Vec3, n: Vec3) -> prism_geometry::Shape {
    Plane::new(p, n).expect("valid plane").into()
}

fn cuboid(min: Vec3, max: Vec3) -> prism_geometry::Shape {
    Cuboid::new(min, max).expect("valid box").into()
}

const I: Transform = Transform::IDENTITY;

/// Ambient + Lambert (+ Phong) at a point of a unit sphere at the origin.
fn phong(p: Vec3, eye: Vec3, m: &Material, albedo: Vec3, ambient: Vec3, l: &PointLight) -> Vec3 {
    let n = p.normalize();
    let to_l = (l.position - p).normalize();
    let v = (eye - p).normalize();
    let mut c = m.ambient * albedo * ambient;
    let ndl = n.dot(to_l);
    if ndl > 0.0 {
        let r = 2.0 * ndl * n - to_l;
        c += l.color * l.intensity * (m.diffuse * ndl * albedo);
        c += l.color * l.intensity * m.specular * r.dot(v).max(0.0).powf(m.shininess) * m.specular_color;
    }
    c
}

fn lit_sphere_case(specular: f32) {
    let albedo = Vec3::new(0.8, 0.6, 0.4);
    let m = Material { ambient: 0.1, diffuse: 0.9, specular, shininess: 20.0, ..Material::diffuse(albedo) };
    let l =
        PointLight { position: Vec3::new(4.0, 3.0, 5.0), color: Vec3::new(1.0, 0.9, 0.8), intensity: 1.2 };
    let eye = Vec3::new(0.0, 0.0, 5.0);
    let cam = camera(eye, Vec3::ZERO, Vec3::Y, 30.0, 41, 41);
    let mut s = scene(vec![(sphere(Vec3::ZERO, 1.0), I, m.clone())], vec![l], cam);
    s.ambient = Vec3::splat(0.3);
    let img = render(&s, 1, 3);
    let mut checked = 0;
    for j in 0..41 {
        for i in 0..41 {
            let ray = cam.ray(i as f32 + 0.5, j as f32 + 0.5);
            let got = px(&img, i, j);
            match sphere_t(ray.origin, ray.dir, Vec3::ZERO, 1.0) {
                Some(t) => {
                    let want = phong(ray.at(t), eye, &m, albedo, s.ambient, &l);
                    assert_close(got, want, 2e-4);
                    checked += 1;
                }
                None if sphere_t(ray.origin, ray.dir, Vec3::ZERO, 1.01).is_none() => {
                    assert_eq!(got, Vec3::ZERO, "background at ({i}, {j})")
                }
                None => {}
            }
        }
    }
    assert!(checked > 300, "only {checked} pixels on the sphere");
}

#[test]
fn lambert_sphere_matches_analytic_shading() {
    lit_sphere_case(0.0);
}

#[test]
fn phong_highlight_matches_its_formula() {
    lit_sphere_case(0.5);
}

/// A floor seen from straight above, lit from (4, 4, 0), with `occluder`
/// on the segment from the floor's centre point to the light.
fn floor_under(occluder: prism_geometry::Shape, material: Material) -> (Vec3, Vec3) {
    let floor_albedo = Vec3::new(0.5, 0.7, 0.9);
    let floor = Material { ambient: 0.2, diffuse: 0.8, ..Material::diffuse(floor_albedo) };
    let l = light(Vec3::new(4.0, 4.0, 0.0));
    let cam = camera(Vec3::new(0.0, 10.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, 20.0, 33, 33);
    let s =
        scene(vec![(plane(Vec3::ZERO, Vec3::Y), I, floor.clone()), (occluder, I, material)], vec![l], cam);
    let img = render(&s, 1, 4);
    let ambient = 0.2 * floor_albedo;
    let direct = 0.8 * floor_albedo * Vec3::Y.dot(l.position.normalize());
    let got = px(&img, 16, 16);
    // got = ambient + shadow · direct: return the measured shadow factor.
    ((got - ambient) / direct, got)
}

#[test]
fn opaque_occluder_leaves_only_ambient() {
    let (shadow, got) = floor_under(sphere(Vec3::new(2.0, 2.0, 0.0), 0.3), Material::diffuse(Vec3::ONE));
    assert_close(got, 0.2 * Vec3::new(0.5, 0.7, 0.9), 1e-6);
    assert_close(shadow, Vec3::ZERO, 1e-6);
}

#[test]
fn unobstructed_floor_is_fully_lit() {
    // The same occluder moved off the segment.
    let (shadow, _) = floor_under(sphere(Vec3::new(2.0, 2.0, 3.0), 0.3), Material::diffuse(Vec3::ONE));
    assert_close(shadow, Vec3::ONE, 1e-5);
}

#[test]
fn transparent_sphere_casts_a_lighter_coloured_shadow_counted_once() {
    let tint = Vec3::new(1.0, 0.5, 0.25);
    let m = Material { transparency: 0.6, ..Material::diffuse(tint) };
    let (shadow, _) = floor_under(sphere(Vec3::new(2.0, 2.0, 0.0), 0.3), m);
    // Once (entering), not twice: 0.6 · tint, not (0.6 · tint)².
    assert_close(shadow, 0.6 * tint, 1e-5);
}

#[test]
fn clear_glass_sphere_casts_no_shadow_and_tinted_glass_a_tinted_one() {
    let (shadow, _) = floor_under(sphere(Vec3::new(2.0, 2.0, 0.0), 0.3), glass(1.5));
    assert_close(shadow, Vec3::ONE, 1e-5);
    let green =
        Material { texture: Texture::Solid(Vec3::new(0.2, 1.0, 0.2)), transmission: 0.7, ..glass(1.5) };
    let (shadow, _) = floor_under(sphere(Vec3::new(2.0, 2.0, 0.0), 0.3), green);
    assert_close(shadow, Vec3::new(0.14, 0.7, 0.14), 1e-5);
}

#[test]
fn absorbing_glass_casts_a_shadow_tinted_by_beer_lambert() {
    // White glass that absorbs red and blue: the light's path through the
    // sphere is its diameter, 0.6 (the segment passes through the centre).
    let absorption = Vec3::new(3.0, 0.2, 3.0);
    let green = Material { absorption, ..glass(1.5) };
    let (shadow, _) = floor_under(sphere(Vec3::new(2.0, 2.0, 0.0), 0.3), green.clone());
    assert_close(shadow, (-absorption * 0.6).exp(), 1e-4);
    assert!(shadow.y > 3.0 * shadow.x, "a green shadow: {shadow}");
    // A box across the segment: the path inside is the box's chord. The
    // segment (t, t, 0) crosses x = 1.5..2.5 and y = 1.8..2.2: t from 1.8
    // to 2.2, length 0.4·√2.
    let slab = cuboid(Vec3::new(1.5, 1.8, -0.5), Vec3::new(2.5, 2.2, 0.5));
    let (shadow, _) = floor_under(slab, green);
    assert_close(shadow, (-absorption * 0.4 * 2f32.sqrt()).exp(), 1e-4);
}

#[test]
fn open_surfaces_count_every_crossing() {
    // A transparent disk across the segment: one crossing.
    let disk = Disk::new(Vec3::new(2.0, 2.0, 0.0), Vec3::new(1.0, 1.0, 0.0), 0.5).expect("valid disk");
    let m = Material { transparency: 0.5, ..Material::diffuse(Vec3::ONE) };
    let (shadow, _) = floor_under(disk.into(), m);
    assert_close(shadow, Vec3::splat(0.5), 1e-5);
}

#[test]
fn mirror_shows_what_it_reflects() {
    // Camera at z = 5 looking at a mirror wall z = 0; behind the camera a
    // flat red sphere that the mirror shows at the image centre.
    let red = Vec3::new(0.9, 0.1, 0.2);
    let blue = Vec3::new(0.0, 0.0, 1.0);
    let mirror = Material { reflectivity: 0.8, ..flat(blue) };
    let cam = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 20.0, 9, 9);
    let s = scene(
        vec![(plane(Vec3::ZERO, Vec3::Z), I, mirror), (sphere(Vec3::new(0.0, 0.0, 12.0), 2.0), I, flat(red))],
        vec![],
        cam,
    );
    let img = render(&s, 1, 2);
    assert_close(px(&img, 4, 4), 0.2 * blue + 0.8 * red, 1e-6);
    // With no recursion the mirror shows only its own colour.
    let img = render(&s, 1, 0);
    assert_close(px(&img, 4, 4), 0.2 * blue, 1e-6);
}

#[test]
fn transparent_sphere_passes_the_ray_straight_through() {
    let m = Material { transparency: 0.7, ..flat(Vec3::new(1.0, 1.0, 0.0)) };
    let wall = Vec3::new(0.1, 0.3, 0.9);
    let cam = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 20.0, 9, 9);
    let s = scene(
        vec![(sphere(Vec3::ZERO, 1.0), I, m), (plane(Vec3::new(0.0, 0.0, -3.0), Vec3::Z), I, flat(wall))],
        vec![],
        cam,
    );
    let img = render(&s, 1, 1);
    // 0.3 · own colour + 0.7 · the wall behind seen through the colour, as
    // a shadow ray through the sphere is tinted: once, the exit not shaded.
    let own = Vec3::new(1.0, 1.0, 0.0);
    assert_close(px(&img, 4, 4), 0.3 * own + 0.7 * own * wall, 1e-6);
}

/// What a see-through surface lets through to the eye is tinted as what it
/// lets through to a lit point (its shadow factor): a colour filter works
/// the same both ways.
#[test]
fn the_view_through_a_coloured_sheet_is_tinted_as_its_shadow() {
    let c = Vec3::new(0.5, 1.0, 0.25);
    let sheet = Material { transparency: 0.6, ..flat(c) };
    let disk = || prism_geometry::Shape::from(Disk::new(Vec3::ZERO, Vec3::Z, 2.0).expect("valid disk"));
    let wall = Vec3::new(0.9, 0.8, 0.7);
    let cam = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 20.0, 9, 9);
    let s = scene(
        vec![(disk(), I, sheet.clone()), (plane(Vec3::new(0.0, 0.0, -3.0), Vec3::Z), I, flat(wall))],
        vec![],
        cam,
    );
    let seen = px(&render(&s, 1, 1), 4, 4);
    // 0.4 · own colour + 0.6 · colour · the wall.
    assert_close(seen, 0.4 * c + 0.6 * c * wall, 1e-6);
    // The same sheet between a floor point and the light: 0.6 · colour.
    let flat_disk =
        prism_geometry::Shape::from(Disk::new(Vec3::new(2.0, 2.0, 0.0), Vec3::Y, 0.3).expect("valid disk"));
    let (shadow, _) = floor_under(flat_disk, sheet.clone());
    assert_close(shadow, 0.6 * c, 1e-5);
    // A filter of its own replaces the colour both ways.
    let f = Vec3::new(1.0, 0.5, 0.0);
    let filtered = Material { filter_color: Some(f), ..sheet };
    let s = scene(
        vec![(disk(), I, filtered.clone()), (plane(Vec3::new(0.0, 0.0, -3.0), Vec3::Z), I, flat(wall))],
        vec![],
        cam,
    );
    assert_close(px(&render(&s, 1, 1), 4, 4), 0.4 * c + 0.6 * f * wall, 1e-6);
    assert_close(floor_under(flat_disk, filtered).0, 0.6 * f, 1e-5);
}

/// Coloured glass tints what is seen through it once per solid, as its
/// shadow is tinted once: where the ray enters, not again where it leaves.
#[test]
fn coloured_glass_tints_the_view_through_it_once() {
    let (n, c) = (1.5f32, Vec3::new(0.2, 0.6, 1.0));
    let slab = cuboid(Vec3::new(-50.0, -50.0, -0.5), Vec3::new(50.0, 50.0, 0.5));
    let wall = Vec3::new(0.9, 0.8, 0.7);
    let cam = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 1.0, 1, 1);
    let tinted = Material { texture: Texture::Solid(c), ..glass(n) };
    let s = scene(
        vec![(slab, I, tinted), (plane(Vec3::new(0.0, 0.0, -3.0), Vec3::Z), I, flat(wall))],
        vec![],
        cam,
    );
    // Depth 2: in, out, and the wall; head-on, F = ((n − 1)/(n + 1))² at
    // each surface.
    let f = ((n - 1.0) / (n + 1.0)).powi(2);
    assert_close(px(&render(&s, 1, 2), 0, 0), (1.0 - f) * (1.0 - f) * c * wall, 2e-4);
}

/// A camera inside coloured glass sees out through it tinted once, where
/// its rays leave the glass (they never entered it).
#[test]
fn a_camera_inside_coloured_glass_sees_out_tinted_once() {
    let (n, c) = (1.5f32, Vec3::new(0.2, 0.6, 1.0));
    let wall = Vec3::new(0.9, 0.8, 0.7);
    let cam = camera(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 1.0, 1, 1);
    let tinted = Material { texture: Texture::Solid(c), ..glass(n) };
    let s = scene(
        vec![
            (sphere(Vec3::ZERO, 10.0), I, tinted),
            (plane(Vec3::new(0.0, 0.0, -20.0), Vec3::Z), I, flat(wall)),
        ],
        vec![],
        cam,
    );
    let f = ((n - 1.0) / (n + 1.0)).powi(2);
    assert_close(px(&render(&s, 1, 1), 0, 0), (1.0 - f) * c * wall, 2e-4);
}

/// A 2×1 black-to-white ramp on the back wall z = −3: the wall's value
/// tells where a ray met it, `value = ((x + 2) / 8 − 0.25) / 0.5`.
fn ramp_wall() -> (prism_geometry::Shape, Material) {
    let ramp =
        prism_shade::ImageTexture::from_linear(2, 1, vec![Vec3::ZERO, Vec3::ONE], prism_shade::Wrap::Clamp)
            .expect("valid texture");
    let t = Texture::Image {
        image: std::sync::Arc::new(ramp),
        mapping: prism_shade::Mapping::Uv,
        scale: prism_geometry::glam::Vec2::new(0.125, 0.125),
        offset: prism_geometry::glam::Vec2::ZERO,
        tint: Vec3::ONE,
    };
    (plane(Vec3::new(-2.0, 0.0, -3.0), Vec3::Z), flat_texture(t))
}

fn wall_x(value: f32) -> f32 {
    (value * 0.5 + 0.25) * 8.0 - 2.0
}

/// Where a straight ray from `eye` along `d` meets the ramp wall (z = −3).
fn wall_x_straight(eye: Vec3, d: Vec3) -> f32 {
    eye.x + d.x * (eye.z + 3.0) / -d.z
}

/// Asserts that the wall's `value` seen along the ray from `eye` along `d`
/// was met `shift` short of the straight ray's point (to 2e-3).
fn assert_wall_hit(value: f32, eye: Vec3, d: Vec3, shift: f32) {
    let (got, want) = (wall_x(value), wall_x_straight(eye, d) - shift);
    assert!((got - want).abs() < 2e-3, "wall hit at {got}, expected {want}");
}

#[test]
fn glass_slab_displaces_the_ray_by_the_analytic_amount() {
    let (n, thick) = (1.5f32, 1.0f32);
    let slab = cuboid(Vec3::new(-50.0, -50.0, -0.5 * thick), Vec3::new(50.0, 50.0, 0.5 * thick));
    let absorption = Vec3::new(0.0, 0.3, 1.0);
    let (wall, wall_m) = ramp_wall();
    let eye = Vec3::new(-3.0, 0.0, 5.0);
    let cam = camera(eye, Vec3::ZERO, Vec3::Y, 10.0, 1, 1);
    let mut s = scene(vec![(slab, I, Material { absorption, ..glass(n) }), (wall, I, wall_m)], vec![], cam);
    // Depth 2: in, out, and the wall; the internal reflections end at depth 2.
    let img = render(&s, 1, 2);
    let d = cam.ray(0.5, 0.5).dir;
    let cos_i = -d.z;
    let (theta_i, theta_t) = (cos_i.acos(), (cos_i.acos().sin() / n).asin());
    let f = prism_shade::optics::fresnel(cos_i, 1.0, n);
    // Beer–Lambert over the path inside: thick / cos θt.
    let inside = thick / theta_t.cos();
    let got = px(&img, 0, 0) / ((1.0 - f) * (1.0 - f));
    let absorbed = (-absorption * inside).exp();
    assert_close(got, got.x * absorbed, 1e-4);
    // Inside the glass the ray runs at θt instead of θi for `thick`.
    let shift = thick * (theta_i.tan() - theta_t.tan());
    // Perpendicular displacement, the textbook form.
    let perp = thick * (theta_i - theta_t).sin() / theta_t.cos();
    assert!((perp - shift * theta_i.cos()).abs() < 1e-5);
    assert!(shift > 0.2);
    assert_wall_hit(got.x, eye, d, shift);
    // And without the slab: straight.
    s.materials[0] = Material { transparency: 1.0, ..flat(Vec3::ONE) };
    let img = render(&s, 1, 2);
    assert_wall_hit(px(&img, 0, 0).x, eye, d, 0.0);
}

#[test]
fn an_air_gap_inside_glass_bends_as_air_in_glass_does() {
    // A glass slab 1 thick with a slab of air 0.4 thick inside it. In the
    // air the ray runs at θi again (1.5 → 1 bends it back), so the
    // displacement is that of 0.6 of glass; the air absorbs nothing.
    let (n, thick, gap) = (1.5f32, 1.0f32, 0.4f32);
    let slab = cuboid(Vec3::new(-50.0, -50.0, -0.5 * thick), Vec3::new(50.0, 50.0, 0.5 * thick));
    let air = cuboid(Vec3::new(-40.0, -40.0, -0.5 * gap), Vec3::new(40.0, 40.0, 0.5 * gap));
    let absorption = Vec3::new(0.0, 0.3, 1.0);
    let (wall, wall_m) = ramp_wall();
    let eye = Vec3::new(-3.0, 0.0, 5.0);
    let cam = camera(eye, Vec3::ZERO, Vec3::Y, 10.0, 1, 1);
    let s = scene(
        vec![(slab, I, Material { absorption, ..glass(n) }), (air, I, glass(1.0)), (wall, I, wall_m)],
        vec![],
        cam,
    );
    // Depth 4: four surfaces, then the wall; a path with any reflection
    // in it reaches the wall deeper than that, and ends.
    let img = render(&s, 1, 4);
    let d = cam.ray(0.5, 0.5).dir;
    let cos_i = -d.z;
    let (theta_i, theta_t) = (cos_i.acos(), (cos_i.acos().sin() / n).asin());
    let (f_in, f_out) =
        (prism_shade::optics::fresnel(cos_i, 1.0, n), prism_shade::optics::fresnel(theta_t.cos(), n, 1.0));
    let got = px(&img, 0, 0) / ((1.0 - f_in) * (1.0 - f_out)).powi(2);
    let absorbed = (-absorption * (thick - gap) / theta_t.cos()).exp();
    assert_close(got, got.x * absorbed, 1e-4);
    assert_wall_hit(got.x, eye, d, (thick - gap) * (theta_i.tan() - theta_t.tan()));
}

/// The ramp wall seen from (−3, 0, 5) toward the origin through `solids`
/// (glass of the index given), one pixel traced to depth `depth`: the
/// wall's value there, the eye and the view direction.
fn ramp_through(solids: Vec<(prism_geometry::Shape, f32)>, depth: u32) -> (f32, Vec3, Vec3) {
    let (wall, wall_m) = ramp_wall();
    let eye = Vec3::new(-3.0, 0.0, 5.0);
    let cam = camera(eye, Vec3::ZERO, Vec3::Y, 10.0, 1, 1);
    let mut objects: Vec<_> = solids.into_iter().map(|(shape, n)| (shape, I, glass(n))).collect();
    objects.push((wall, I, wall_m));
    let img = render(&scene(objects, vec![], cam), 1, depth);
    (px(&img, 0, 0).x, eye, cam.ray(0.5, 0.5).dir)
}

#[test]
fn a_liquid_overlapping_its_glass_wall_bends_once_at_each_interface() {
    // Liquid (1.33) from z = 0.8 down to −0.3, overlapping the glass wall
    // (1.5) from z = 0.5 to −0.5: air → liquid at 0.8, liquid → glass at
    // 0.5 (the glass, entered last, counts), no surface where the liquid
    // ends inside the glass at −0.3, glass → air at −0.5. So 0.3 of liquid
    // and the 1.0 of glass displace the ray.
    let (n_glass, n_liquid) = (1.5f32, 1.33f32);
    let wall_of_glass = cuboid(Vec3::new(-50.0, -50.0, -0.5), Vec3::new(50.0, 50.0, 0.5));
    let liquid = cuboid(Vec3::new(-40.0, -40.0, -0.3), Vec3::new(40.0, 40.0, 0.8));
    let (value, eye, d) = ramp_through(vec![(liquid, n_liquid), (wall_of_glass, n_glass)], 4);
    let cos_i = -d.z;
    let theta_i = cos_i.acos();
    let (theta_l, theta_g) = ((theta_i.sin() / n_liquid).asin(), (theta_i.sin() / n_glass).asin());
    let f = prism_shade::optics::fresnel;
    let w = (1.0 - f(cos_i, 1.0, n_liquid))
        * (1.0 - f(theta_l.cos(), n_liquid, n_glass))
        * (1.0 - f(theta_g.cos(), n_glass, 1.0));
    let shift = 0.3 * (theta_i.tan() - theta_l.tan()) + 1.0 * (theta_i.tan() - theta_g.tan());
    assert_wall_hit(value / w, eye, d, shift);
}

#[test]
fn a_camera_in_glass_inside_water_bends_into_the_water_then_the_air() {
    // The eye inside a glass block (1.5, z from −0.5 to 8) inside a water
    // block (1.33, z from −2.5 to 10): the view ray leaves the glass into
    // the water at z = −0.5, the water into air at z = −2.5, and meets the
    // wall at z = −3. It runs at θg for 5.5, θw for 2 and θa for 0.5.
    let (n_glass, n_water) = (1.5f32, 1.33f32);
    let glass_block = cuboid(Vec3::new(-40.0, -40.0, -0.5), Vec3::new(40.0, 40.0, 8.0));
    let water = cuboid(Vec3::new(-50.0, -50.0, -2.5), Vec3::new(50.0, 50.0, 10.0));
    // Depth 2: two surfaces, then the wall; the reflected parts end on
    // the blocks' faces, black.
    let (value, eye, d) = ramp_through(vec![(water, n_water), (glass_block, n_glass)], 2);
    let sin_g = (1.0 - d.z * d.z).sqrt();
    let (sin_w, sin_a) = (sin_g * n_glass / n_water, sin_g * n_glass);
    let (cos_g, cos_w) = ((1.0 - sin_g * sin_g).sqrt(), (1.0 - sin_w * sin_w).sqrt());
    let tan = |s: f32| s / (1.0 - s * s).sqrt();
    let f = prism_shade::optics::fresnel;
    let w = (1.0 - f(cos_g, n_glass, n_water)) * (1.0 - f(cos_w, n_water, 1.0));
    let shift = 2.0 * (tan(sin_g) - tan(sin_w)) + 0.5 * (tan(sin_g) - tan(sin_a));
    assert!(shift < -0.5, "{shift}");
    assert_wall_hit(value / w, eye, d, shift);
}

#[test]
fn an_object_inside_absorbing_glass_is_seen_through_it() {
    // A white ball inside a block of absorbing glass of index 1 (no bending,
    // no reflection): the view ray crosses 1.5 of glass before the ball.
    let absorption = Vec3::new(0.5, 1.0, 0.0);
    let block = cuboid(Vec3::splat(-2.0), Vec3::splat(2.0));
    let cam = camera(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y, 1.0, 1, 1);
    let s = scene(
        vec![
            (block, I, Material { absorption, ..glass(1.0) }),
            (sphere(Vec3::ZERO, 0.5), I, flat(Vec3::ONE)),
        ],
        vec![],
        cam,
    );
    assert_close(px(&render(&s, 1, 4), 0, 0), (-absorption * 1.5).exp(), 1e-5);
    // A clear ball of glass inside instead: absorbed over the block's
    // length less the ball's, onto a white wall behind.
    let s = scene(
        vec![
            (cuboid(Vec3::splat(-2.0), Vec3::splat(2.0)), I, Material { absorption, ..glass(1.0) }),
            (sphere(Vec3::ZERO, 0.5), I, glass(1.0)),
            (plane(Vec3::new(0.0, 0.0, -5.0), Vec3::Z), I, flat(Vec3::ONE)),
        ],
        vec![],
        cam,
    );
    assert_close(px(&render(&s, 1, 8), 0, 0), (-absorption * 3.0).exp(), 1e-5);
}

/// A camera inside a wide glass block looks up at its top face at
/// `angle` from the normal; above the block a red ceiling.
fn inside_glass(angle_deg: f32) -> (Vec3, f32) {
    let n = 1.5;
    let a = angle_deg.to_radians();
    let block = cuboid(Vec3::new(-1e4, -1e4, -1e4), Vec3::new(1e4, 1.0, 1e4));
    let red = Vec3::new(1.0, 0.0, 0.0);
    let cam = camera(Vec3::ZERO, Vec3::new(a.sin(), a.cos(), 0.0), Vec3::Z, 10.0, 1, 1);
    let s = scene(
        vec![(block, I, glass(n)), (plane(Vec3::new(0.0, 3.0, 0.0), Vec3::NEG_Y), I, flat(red))],
        vec![],
        cam,
    );
    let img = render(&s, 1, 1);
    (px(&img, 0, 0), prism_shade::optics::fresnel(a.cos(), n, 1.0))
}

#[test]
fn total_internal_reflection_past_the_critical_angle() {
    let critical = (1.0f32 / 1.5).asin().to_degrees();
    for a in [0.0, 20.0, critical - 1.0] {
        let (got, f) = inside_glass(a);
        assert!(f < 1.0);
        assert_close(got, (1.0 - f) * Vec3::X, 1e-5);
        assert!(got.x > 0.0, "refracts at {a}°");
    }
    for a in [critical + 1.0, 60.0, 80.0] {
        let (got, _) = inside_glass(a);
        assert_eq!(got, Vec3::ZERO, "total internal reflection at {a}°");
    }
}

/// A flat wall at distance `d` straight ahead, seen through `fog`.
fn fogged_wall(d: f32, mode: prism_shade::FogMode, enabled: bool) -> Vec3 {
    let cam = camera(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 10.0, 1, 1);
    let mut s = scene(
        vec![(plane(Vec3::new(0.0, 0.0, -d), Vec3::Z), I, flat(Vec3::new(0.2, 0.4, 0.6)))],
        vec![],
        cam,
    );
    s.fog = fog(Vec3::new(0.9, 0.8, 0.7), mode);
    s.fog_on = enabled;
    px(&render(&s, 1, 1), 0, 0)
}

#[test]
fn linear_fog_at_start_and_end() {
    let obj = Vec3::new(0.2, 0.4, 0.6);
    let fogc = Vec3::new(0.9, 0.8, 0.7);
    use prism_shade::FogMode::Linear;
    assert_close(fogged_wall(4.0, Linear { start: 4.0, end: 12.0 }, true), obj, 1e-6);
    assert_close(fogged_wall(4.0, Linear { start: 5.0, end: 12.0 }, true), obj, 1e-6);
    assert_close(fogged_wall(12.0, Linear { start: 4.0, end: 12.0 }, true), fogc, 1e-6);
    assert_close(fogged_wall(20.0, Linear { start: 4.0, end: 12.0 }, true), fogc, 1e-6);
    assert_close(fogged_wall(8.0, Linear { start: 4.0, end: 12.0 }, true), 0.5 * (obj + fogc), 1e-5);
    // Switched off: no effect.
    assert_close(fogged_wall(12.0, Linear { start: 4.0, end: 12.0 }, false), obj, 1e-6);
}

#[test]
fn exponential_fog_laws() {
    let obj = Vec3::new(0.2, 0.4, 0.6);
    let fogc = Vec3::new(0.9, 0.8, 0.7);
    let (d, rho) = (7.0f32, 0.13f32);
    let t = (-rho * d).exp();
    let got = fogged_wall(d, prism_shade::FogMode::Exponential { density: rho }, true);
    assert_close(got, t * obj + (1.0 - t) * fogc, 1e-5);
    let t2 = (-(rho * d) * (rho * d)).exp();
    let got = fogged_wall(d, prism_shade::FogMode::ExponentialSquared { density: rho }, true);
    assert_close(got, t2 * obj + (1.0 - t2) * fogc, 1e-5);
}

#[test]
fn fog_covers_misses_and_reflected_segments() {
    let fogc = Vec3::new(0.9, 0.8, 0.7);
    let red = Vec3::new(0.9, 0.1, 0.2);
    // Mirror 2 ahead; it reflects a sphere whose near side is at z = 4:
    // the path is 2 + 6 = 8 long.
    let cam = camera(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 10.0, 1, 1);
    let mirror = Material { reflectivity: 1.0, ..flat(Vec3::ZERO) };
    let mut s = scene(
        vec![
            (plane(Vec3::new(0.0, 0.0, -2.0), Vec3::Z), I, mirror),
            (sphere(Vec3::new(0.0, 0.0, 5.0), 1.0), I, flat(red)),
        ],
        vec![],
        cam,
    );
    let rho = 0.1f32;
    s.fog = fog(fogc, prism_shade::FogMode::Exponential { density: rho });
    let t = (-rho * 8.0).exp();
    assert_close(px(&render(&s, 1, 1), 0, 0), t * red + (1.0 - t) * fogc, 1e-5);
    // Linear: the reflection is as foggy as its path length 8 of 10.
    s.fog = fog(fogc, prism_shade::FogMode::Linear { start: 0.0, end: 10.0 });
    assert_close(px(&render(&s, 1, 1), 0, 0), 0.2 * red + 0.8 * fogc, 1e-5);
    // A ray that hits nothing (looking along +Z beside the sphere) is all fog.
    s.camera = camera(Vec3::new(5.0, 0.0, 0.0), Vec3::new(5.0, 0.0, 1.0), Vec3::Y, 10.0, 1, 1);
    assert_close(px(&render(&s, 1, 1), 0, 0), fogc, 1e-6);
    s.fog = None;
    assert_close(px(&render(&s, 1, 1), 0, 0), s.background, 0.0);
}

#[test]
fn sphere_texture_follows_the_documented_formula() {
    let image = distinct_texture();
    let tex = |mapping| Texture::Image {
        image: image.clone(),
        mapping,
        scale: prism_geometry::glam::Vec2::ONE,
        offset: prism_geometry::glam::Vec2::ZERO,
        tint: Vec3::ONE,
    };
    let cam = camera(Vec3::new(1.0, 2.0, 5.0), Vec3::ZERO, Vec3::Y, 30.0, 31, 31);
    let s =
        scene(vec![(sphere(Vec3::ZERO, 1.0), I, flat_texture(tex(prism_shade::Mapping::Uv)))], vec![], cam);
    let img = render(&s, 1, 0);
    let mut checked = 0;
    for j in 0..31 {
        for i in 0..31 {
            let ray = cam.ray(i as f32 + 0.5, j as f32 + 0.5);
            let Some(t) = sphere_t(ray.origin, ray.dir, Vec3::ZERO, 1.0) else { continue };
            let d = ray.at(t).normalize();
            let u = 0.5 + d.x.atan2(d.z) / (2.0 * std::f32::consts::PI);
            let v = 0.5 - d.y.asin() / std::f32::consts::PI;
            let want = image.sample(prism_geometry::glam::Vec2::new(u, v));
            assert_close(px(&img, i, j), want, 2e-3);
            checked += 1;
        }
    }
    assert!(checked > 150);
    // The object-space spherical mapping of a unit sphere moved by a
    // transform gives the same picture.
    let moved = Transform::translate(Vec3::new(3.0, 0.0, 0.0)).expect("finite");
    let cam2 = camera(Vec3::new(4.0, 2.0, 5.0), Vec3::new(3.0, 0.0, 0.0), Vec3::Y, 30.0, 31, 31);
    let s2 = scene(
        vec![(sphere(Vec3::ZERO, 1.0), moved, flat_texture(tex(prism_shade::Mapping::Spherical)))],
        vec![],
        cam2,
    );
    let img2 = render(&s2, 1, 0);
    for (a, b) in img.pixels.iter().zip(&img2.pixels) {
        assert_close(*a, *b, 2e-3);
    }
    // So does a sphere made about its centre (3, 0, 0), with no transform:
    // the mapping is about the shape's own centre, not the world's origin.
    let s3 = scene(
        vec![(sphere(Vec3::new(3.0, 0.0, 0.0), 1.0), I, flat_texture(tex(prism_shade::Mapping::Spherical)))],
        vec![],
        cam2,
    );
    let img3 = render(&s3, 1, 0);
    for (a, b) in img.pixels.iter().zip(&img3.pixels) {
        assert_close(*a, *b, 2e-3);
    }
}

#[test]
fn cylindrical_mapping_is_about_the_shapes_own_axis() {
    // A cylinder made at base (3, -1, 0) maps as one made at the origin and
    // moved there: about its own axis (x = 3, z = 0), not the world's Y axis.
    let tex = flat_texture(Texture::Image {
        image: distinct_texture(),
        mapping: prism_shade::Mapping::Cylindrical,
        scale: prism_geometry::glam::Vec2::ONE,
        offset: prism_geometry::glam::Vec2::ZERO,
        tint: Vec3::ONE,
    });
    let cam = camera(Vec3::new(4.0, 1.0, 6.0), Vec3::new(3.0, 0.0, 0.0), Vec3::Y, 40.0, 31, 31);
    let cylinder = |base| prism_geometry::Shape::from(Cylinder::new(base, 1.0, 2.0).expect("valid cylinder"));
    let moved = Transform::translate(Vec3::new(3.0, -1.0, 0.0)).expect("finite");
    let a = render(&scene(vec![(cylinder(Vec3::ZERO), moved, tex.clone())], vec![], cam), 1, 0);
    let b = render(&scene(vec![(cylinder(Vec3::new(3.0, -1.0, 0.0)), I, tex)], vec![], cam), 1, 0);
    let seen = a.pixels.iter().filter(|p| **p != Vec3::ZERO).count();
    assert!(seen > 200, "only {seen} pixels on the cylinder");
    for (a, b) in a.pixels.iter().zip(&b.pixels) {
        assert_close(*a, *b, 2e-3);
    }
}

#[test]
fn world_checker_floor() {
    let a = Vec3::new(1.0, 1.0, 1.0);
    let b = Vec3::new(0.1, 0.0, 0.0);
    let t = Texture::Checker { a, b, size: 1.0, world: true };
    let cam = camera(Vec3::new(0.25, 10.0, 0.25), Vec3::new(0.25, 0.0, 0.25), Vec3::NEG_Z, 0.5, 1, 1);
    let mut s = scene(vec![(plane(Vec3::ZERO, Vec3::Y), I, flat_texture(t))], vec![], cam);
    assert_close(px(&render(&s, 1, 0), 0, 0), a, 0.0);
    s.camera = camera(Vec3::new(1.25, 10.0, 0.25), Vec3::new(1.25, 0.0, 0.25), Vec3::NEG_Z, 0.5, 1, 1);
    assert_close(px(&render(&s, 1, 0), 0, 0), b, 0.0);
    s.camera = camera(Vec3::new(-0.75, 10.0, -0.75), Vec3::new(-0.75, 0.0, -0.75), Vec3::NEG_Z, 0.5, 1, 1);
    assert_close(px(&render(&s, 1, 0), 0, 0), a, 0.0);
}

#[test]
fn a_sun_through_nested_absorbing_solids_follows_beer_lambert() {
    // Sunlight at 45° through a glass box with a box of other glass inside
    // it, beside the camera's view. From the floor's centre toward the sun
    // the segment crosses 3√2 of the outer box, √2 of it inside the inner
    // one: the inner glass replaces the outer there.
    let floor_albedo = Vec3::new(0.5, 0.7, 0.9);
    let floor = Material { ambient: 0.2, diffuse: 0.8, ..Material::diffuse(floor_albedo) };
    let a = Material { absorption: Vec3::splat(0.6), ..glass(1.5) };
    let b = Material { absorption: Vec3::splat(0.1), ..glass(1.5) };
    let sun = prism_shade::Light {
        kind: prism_shade::LightKind::Directional { direction: Vec3::new(-1.0, -1.0, 0.0).normalize() },
        color: Vec3::ONE,
        intensity: 1.0,
    };
    let cam = camera(Vec3::new(0.0, 10.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, 20.0, 33, 33);
    let s = scene_lit(
        vec![
            (plane(Vec3::ZERO, Vec3::Y), I, floor),
            (cuboid(Vec3::new(1.0, 1.0, -0.5), Vec3::new(4.0, 4.0, 0.5)), I, a),
            (cuboid(Vec3::new(2.0, 2.0, -0.4), Vec3::new(3.0, 3.0, 0.4)), I, b),
        ],
        vec![sun],
        cam,
    );
    let got = px(&render(&s, 1, 4), 16, 16);
    let shadow = (got - 0.2 * floor_albedo) / (0.8 * floor_albedo * std::f32::consts::FRAC_1_SQRT_2);
    let r2 = std::f32::consts::SQRT_2;
    assert_close(shadow, Vec3::splat((-(0.6 * 2.0 * r2 + 0.1 * r2)).exp()), 1e-4);
}

#[test]
fn an_opaque_room_blocks_the_light_outside_whatever_else_is_see_through() {
    // The floor and the camera inside a closed opaque box, the light
    // outside: the shadow ray leaves the room through its inner (back)
    // face, which blocks it. A glass sphere elsewhere in the scene makes
    // the shadows walk their crossings; that must not open the walls.
    let floor_albedo = Vec3::new(0.5, 0.7, 0.9);
    let floor = Material { ambient: 0.2, diffuse: 0.8, ..Material::diffuse(floor_albedo) };
    let room = cuboid(Vec3::new(-1.0, -0.5, -1.0), Vec3::new(1.0, 1.0, 1.0));
    let cam = camera(Vec3::new(0.0, 0.9, 0.0), Vec3::ZERO, Vec3::NEG_Z, 20.0, 9, 9);
    let l = light(Vec3::new(4.0, 4.0, 0.0));
    let mut objects = vec![(plane(Vec3::ZERO, Vec3::Y), I, floor), (room, I, Material::diffuse(Vec3::ONE))];
    let dark = px(&render(&scene(objects.clone(), vec![l], cam), 1, 4), 4, 4);
    assert_close(dark, 0.2 * floor_albedo, 1e-6);
    objects.push((sphere(Vec3::new(-20.0, 5.0, -20.0), 1.0), I, glass(1.5)));
    let with_glass = px(&render(&scene(objects, vec![l], cam), 1, 4), 4, 4);
    assert_close(with_glass, dark, 0.0);
}

#[test]
fn absorption_counts_only_segments_inside_a_closed_solid() {
    // Straight down the axis onto a white wall behind the object, the
    // glass index-matched (ior 1: no bending, no reflection head on).
    let a = Vec3::new(0.5, 0.2, 0.1);
    let wall = (plane(Vec3::new(0.0, 0.0, -5.0), Vec3::Z), I, flat(Vec3::ONE));
    let cam = camera(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y, 0.5, 1, 1);
    let seen = |object: prism_geometry::Shape, m: Material| {
        px(&render(&scene(vec![wall.clone(), (object, I, m)], vec![], cam), 1, 8), 0, 0)
    };
    // An open disk seen from behind: no inside, nothing absorbed (the ray
    // came 10 units through air, not glass).
    let disk = Disk::new(Vec3::ZERO, Vec3::NEG_Z, 1.0).expect("valid disk");
    assert_close(seen(disk.into(), Material { absorption: a, ..glass(1.0) }), Vec3::ONE, 1e-5);
    // A unit sphere, half see-through and half glass: both the unbent and
    // the refracted ray cross its diameter inside, and both are absorbed.
    let m = Material { transparency: 0.5, transmission: 0.5, absorption: a, ..glass(1.0) };
    assert_close(seen(sphere(Vec3::ZERO, 1.0), m), (-2.0 * a).exp(), 1e-4);
}

#[test]
fn index_matched_glass_is_invisible() {
    // A clear ior-1 sphere before a wall of two colours: no bending and no
    // reflection at any angle, so the picture is the wall's, rim included.
    let wall = cuboid(Vec3::new(-5.0, -5.0, -4.0), Vec3::new(5.0, 5.0, -3.0));
    let ramp = Material {
        texture: Texture::Checker { a: Vec3::ONE, b: Vec3::ZERO, size: 0.7, world: false },
        ..flat(Vec3::ONE)
    };
    let cam = camera(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y, 12.0, 41, 41);
    let bare = render(&scene(vec![(wall, I, ramp.clone())], vec![], cam), 1, 8);
    let shot = scene(vec![(wall, I, ramp), (sphere(Vec3::ZERO, 0.9), I, glass(1.0))], vec![], cam);
    let with = render(&shot, 1, 8);
    for (a, b) in bare.pixels.iter().zip(&with.pixels) {
        assert_close(*b, *a, 1e-5);
    }
}

#[test]
fn a_shadow_ray_through_a_meshs_shared_edge_crosses_it_once() {
    // A transparent quad of two triangles above a floor point, the light
    // straight above: the shadow ray runs exactly along x = z = 0, through
    // the quad's diagonal, where both triangles report the crossing. The
    // surface is crossed once: half the light, not a quarter.
    use prism_bvh::{Accel, Object};
    use std::sync::Arc;
    let quad = prism_geometry::TriangleMesh::new(
        vec![
            Vec3::new(-1.0, 2.0, -1.0),
            Vec3::new(1.0, 2.0, -1.0),
            Vec3::new(1.0, 2.0, 1.0),
            Vec3::new(-1.0, 2.0, 1.0),
        ],
        None,
        None,
        vec![[0, 2, 1], [0, 3, 2]],
    )
    .expect("valid mesh");
    let floor = Material { ambient: 0.0, diffuse: 1.0, ..Material::diffuse(Vec3::ONE) };
    let see_through = Material { transparency: 0.5, ..Material::diffuse(Vec3::ONE) };
    let lit = |with_quad: bool| {
        let mut objects = vec![Object::Shape(prism_geometry::Instance::new(plane(Vec3::ZERO, Vec3::Y), I))];
        if with_quad {
            objects.push(Object::Mesh { mesh: 0, transform: I });
        }
        let scene = prism_shade::Scene {
            accel: Accel::build(vec![Arc::new(quad.clone())], objects).expect("builds"),
            object_materials: vec![0, 1],
            materials: vec![floor.clone(), see_through.clone()],
            lights: vec![light(Vec3::new(0.0, 4.0, 0.0)).into()],
            ambient: Vec3::ZERO,
            background: Vec3::ZERO,
            environment: None,
            fog: None,
        };
        // From the side, under the quad, onto the floor point (0, 0, 0).
        let cam = camera(Vec3::new(5.0, 1.0, 0.0), Vec3::ZERO, Vec3::Y, 0.5, 1, 1);
        let s = prism_shade::RenderSettings {
            camera: cam,
            fog: false,
            spp: 1,
            max_depth: 2,
            min_contribution: 0.0,
            threads: Some(1),
            antialias: prism_shade::Antialias::default(),
        };
        px(&prism_shade::render(&scene, &s, prism_shade::RenderHooks::default()).0, 0, 0)
    };
    let (open, shaded) = (lit(false), lit(true));
    assert!(open.x > 0.01, "{open}");
    assert_close(shaded / open, Vec3::splat(0.5), 1e-4);
}

#[test]
fn a_ray_through_a_closed_meshs_corner_is_shaded_once() {
    // A see-through octahedron (a closed mesh) and glass one, seen along
    // the Z axis exactly through the corner at (0, 0, 1), where four
    // triangles meet: the surface is entered there once. Half-transparent
    // and flat white, the corner pixel is 0.5 like its neighbours, not 0.75.
    use prism_bvh::{Accel, Object};
    use std::sync::Arc;
    let corners = vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::NEG_X, Vec3::NEG_Y, Vec3::NEG_Z];
    let faces = vec![[0, 1, 2], [1, 3, 2], [3, 4, 2], [4, 0, 2], [1, 0, 5], [3, 1, 5], [4, 3, 5], [0, 4, 5]];
    let gem = prism_geometry::TriangleMesh::new(corners, None, None, faces).expect("valid mesh");
    assert!(gem.is_closed());
    let shot = |m: Material| {
        let scene = prism_shade::Scene {
            accel: Accel::build(vec![Arc::new(gem.clone())], vec![Object::Mesh { mesh: 0, transform: I }])
                .expect("builds"),
            object_materials: vec![0],
            materials: vec![m],
            lights: vec![],
            ambient: Vec3::ONE,
            background: Vec3::new(0.2, 0.4, 0.6),
            environment: None,
            fog: None,
        };
        let s = prism_shade::RenderSettings {
            camera: camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 20.0, 21, 21),
            fog: false,
            spp: 1,
            max_depth: 8,
            min_contribution: 0.0,
            threads: Some(1),
            antialias: prism_shade::Antialias::default(),
        };
        prism_shade::render(&scene, &s, prism_shade::RenderHooks::default()).0
    };
    let img = shot(Material { transparency: 0.5, ..flat(Vec3::ONE) });
    let want = 0.5 * Vec3::ONE + 0.5 * Vec3::new(0.2, 0.4, 0.6);
    assert_close(px(&img, 10, 10), want, 1e-5);
    assert_close(px(&img, 11, 10), want, 1e-5);
    // Index-matched absorbing glass: no bending, no reflection, so the
    // corner's ray is absorbed over the octahedron's axis, 2 long, once.
    let absorption = Vec3::new(0.1, 0.2, 0.3);
    let img = shot(Material { absorption, ..glass(1.0) });
    assert_close(px(&img, 10, 10), Vec3::new(0.2, 0.4, 0.6) * (-absorption * 2.0).exp(), 1e-4);
}

#[test]
fn a_ray_that_leaves_absorbing_glass_by_a_bent_normal_is_not_absorbed_outside_it() {
    // A glass cube mesh whose top face's shading normal leans 45° toward
    // +Z. A ray inside meets the top beyond the critical angle; its
    // reflection about the leaning normal goes out through the top. Out
    // there it is outside the glass: a ceiling at y = 1.5 and one at y = 6
    // look the same through it (before, the glass absorbed the way up).
    use prism_bvh::{Accel, Object};
    use std::sync::Arc;
    let corners =
        [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]];
    let quads: [([usize; 4], Vec3); 6] = [
        ([4, 5, 6, 7], Vec3::Z),
        ([1, 0, 3, 2], Vec3::NEG_Z),
        ([5, 1, 2, 6], Vec3::X),
        ([0, 4, 7, 3], Vec3::NEG_X),
        ([7, 6, 2, 3], Vec3::new(0.0, 1.0, 1.0).normalize()),
        ([0, 1, 5, 4], Vec3::NEG_Y),
    ];
    let (mut positions, mut normals, mut faces) = (Vec::new(), Vec::new(), Vec::new());
    for (quad, n) in quads {
        let base = positions.len() as u32;
        for k in quad {
            positions.push(Vec3::from_array(corners[k].map(|c| c as f32)));
            normals.push(n);
        }
        faces.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
    }
    let cube = prism_geometry::TriangleMesh::new(positions, Some(normals), None, faces).expect("valid mesh");
    assert!(cube.is_closed());
    let glass = Material { absorption: Vec3::new(0.0, 0.5, 0.5), ..glass(1.5) };
    let seen = |ceiling: f32| {
        let objects = vec![
            Object::Mesh { mesh: 0, transform: I },
            Object::Shape(prism_geometry::Instance::new(plane(Vec3::new(0.0, ceiling, 0.0), Vec3::NEG_Y), I)),
        ];
        let scene = prism_shade::Scene {
            accel: Accel::build(vec![Arc::new(cube.clone())], objects).expect("builds"),
            object_materials: vec![0, 1],
            materials: vec![glass.clone(), flat(Vec3::ONE)],
            lights: vec![],
            ambient: Vec3::ONE,
            background: Vec3::ZERO,
            environment: None,
            fog: None,
        };
        let s = prism_shade::RenderSettings {
            camera: camera(Vec3::new(0.0, 0.0, 6.0), Vec3::new(0.0, 0.8, 1.0), Vec3::Y, 0.01, 1, 1),
            fog: false,
            spp: 1,
            max_depth: 6,
            min_contribution: 0.0,
            threads: Some(1),
            antialias: prism_shade::Antialias::default(),
        };
        px(&prism_shade::render(&scene, &s, prism_shade::RenderHooks::default()).0, 0, 0)
    };
    let (near, far) = (seen(1.5), seen(6.0));
    assert!(near.y > 0.1, "the ceiling is seen: {near}");
    assert_close(far, near, 1e-5);
}

#[test]
fn a_point_inside_a_see_through_solid_is_lit_through_its_surface_once() {
    // A floor point inside a large transparent sphere, the light outside:
    // the shadow ray leaves the sphere without entering it, and its light
    // is dimmed there once, by 0.6 · tint, as a point outside it behind it.
    let floor_albedo = Vec3::new(0.5, 0.7, 0.9);
    let floor = Material { ambient: 0.2, diffuse: 0.8, ..Material::diffuse(floor_albedo) };
    let tint = Vec3::new(1.0, 0.5, 0.25);
    let case = Material { transparency: 0.6, ..Material::diffuse(tint) };
    let l = light(Vec3::new(4.0, 4.0, 0.0));
    let cam = camera(Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, 20.0, 9, 9);
    let shot = |objects| px(&render(&scene(objects, vec![l], cam), 1, 4), 4, 4);
    let bare = shot(vec![(plane(Vec3::ZERO, Vec3::Y), I, floor.clone())]);
    let cased = shot(vec![(plane(Vec3::ZERO, Vec3::Y), I, floor), (sphere(Vec3::ZERO, 3.0), I, case)]);
    let ambient = 0.2 * floor_albedo;
    assert_close((cased - ambient) / (bare - ambient), 0.6 * tint, 1e-4);
}

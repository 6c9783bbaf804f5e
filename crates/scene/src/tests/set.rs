//! `--set KEY=VALUE` (`LoadOptions::sets`): values replaced, keys and
//! tables added, errors naming the flag, and the file's own lines kept for
//! every other error.

use super::*;

/// The base scene with a plane (`objects.0`) and a red sphere (`objects.1`).
fn scene() -> String {
    format!(
        "{BASE}[[objects]]\ntype = \"plane\"\n\n[[objects]]\ntype = \"sphere\"\ncenter = [0, 1, 0]\nradius = 1\nmaterial = \"red\"\n"
    )
}

/// `s.toml:LINE:COL` of the first `needle` in `text`.
fn place(text: &str, needle: &str) -> String {
    let (line, col) = line_col(text, text.find(needle).unwrap());
    format!("s.toml:{line}:{col}")
}

fn with_sets(text: &str, sets: &[&str]) -> Result<LoadedScene, SceneError> {
    let opts = LoadOptions { sets: sets.iter().map(|s| (*s).to_owned()).collect(), ..LoadOptions::default() };
    parse_scene_str_with(text, Path::new("."), Path::new("s.toml"), &opts)
}

fn set_err(text: &str, sets: &[&str]) -> String {
    with_sets(text, sets).unwrap_err().to_string()
}

#[test]
fn sets_replace_values_add_keys_and_tables() {
    let plain = with_sets(&scene(), &[]).unwrap();
    assert_eq!(plain.settings.spp, 2);
    let l = with_sets(
        &scene(),
        &[
            "render.spp=16",
            "render.max_depth=3",
            "camera.position.2 = 9",
            "objects.1.radius=0.5",
            "materials.red.color=[0, 0, 1]",
            "materials.blue.color=\"#00ff00\"",
            "objects.0.material=blue",
            "render.width=20",
        ],
    )
    .unwrap();
    assert_eq!(l.settings.spp, 16);
    assert_eq!(l.settings.max_depth, 3);
    assert_eq!(l.settings.camera.size(), (20, 180));
    assert_eq!(l.settings.camera.position(), prism_geometry::glam::Vec3::new(0.0, 2.0, 9.0));
    assert_eq!(l.info.materials, ["blue", "red"], "the plane uses blue: no default material");
    // The sphere's radius: its bounds.
    assert_eq!(l.info.bounds.max, prism_geometry::glam::Vec3::new(0.5, 1.5, 0.5));
    // The last set of a key wins; a key of a table the file lacks makes the table.
    let l = with_sets(&scene(), &["render.spp=2", "render.spp=5"]).unwrap();
    assert_eq!(l.settings.spp, 5);
    let no_render = scene().replace("[render]\nwidth = 320\nheight = 180\nspp = 2\n", "");
    let l = with_sets(&no_render, &["render.spp=7"]).unwrap();
    assert_eq!(l.settings.spp, 7);
    let fog = format!("{}[fog]\nend = 20\n", scene());
    assert!(with_sets(&fog, &[]).unwrap().settings.fog);
    assert!(!with_sets(&fog, &["fog.enabled=false"]).unwrap().settings.fog);
    // Keys two levels below a table the file lacks (written as dotted keys,
    // which toml 0.8 refused with "expected a borrowed string").
    let l = with_sets(&scene(), &["objects.1.material=checks", "materials.checks.texture.type=\"checker\""])
        .unwrap();
    assert_eq!(l.info.materials, ["checks", "red", "(default)"]);
    let l = with_sets(&scene(), &["materials.red.texture.type=\"checker\""]);
    assert!(l.unwrap_err().to_string().contains("`color` or `texture`, not both"));
}

#[test]
fn sets_read_the_scene_as_toml_1_1_as_the_load_does() {
    // A trailing comma and a line break inside an inline table (TOML 1.1).
    let text = scene().replace("radius = 1\n", "radius = 1\ntransform = [{\n  scale = 2,\n}]\n");
    assert_ne!(text, scene());
    with_sets(&text, &[]).unwrap();
    let l = with_sets(&text, &["render.spp=4", "objects.1.transform.0.scale=3"]).unwrap();
    assert_eq!(l.settings.spp, 4);
    assert_eq!(l.info.bounds.max.x, 3.0, "the sphere scaled by 3 about the origin");
}

#[test]
fn problems_in_a_set_name_the_flag() {
    for (sets, words) in [
        (&["render.spp=0"][..], "--set: render.spp=0: spp (samples per pixel) must be at least 1"),
        (&["render.spp"], "--set: render.spp: expected KEY=VALUE"),
        (&["render.sp=3"], "--set: render.sp=3: unknown key `sp`; did you mean `spp`?"),
        (
            &["render.spp=many"],
            "--set: render.spp=many: expected a whole number (0 or more), got the string \"many\"",
        ),
        (
            &["objects.9.radius=1"],
            "--set: objects.9.radius=1: `objects` has 2 entries (0 to 1), there is no entry 9",
        ),
        (&["objects.x.radius=1"], "`objects` is a list; expected an index from 0, got `x`"),
        (
            &["lights.3.intensity=1"],
            "--set: lights.3.intensity=1: `lights` has 1 entry (0), there is no entry 3",
        ),
        (
            &["objects=5"],
            "--set: objects=5: `objects` is a list of tables; set one entry's key (such as objects.0.KEY=VALUE)",
        ),
        (&["render=3"], "`render` is a table; set its keys one by one"),
        (&["render.spp.x=1"], "`render.spp` is a number, not a table"),
        (&["objects.1.radios=1"], "unknown key `radios` in a sphere; did you mean `radius`?"),
        (&["fog.start=1"], "--set: fog.start=1: linear fog needs `end`"),
        // An index into a list the scene does not have.
        (
            &["objects.0.center.1=2"],
            "--set: objects.0.center.1=2: `objects.0.center` is not in the scene, so it has no entry 1; set the whole list (such as objects.0.center=[…])",
        ),
        (&["fog.color.0=1"], "`fog.color` is not in the scene, so it has no entry 0"),
        // A part of an array set: the error about the whole array is the set's.
        (
            &["camera.position.1=nan"],
            "--set: camera.position.1=nan: camera position must be three finite numbers, got [0.0, NaN, 10.0]",
        ),
        (
            &["objects.1.center.0=1e39"],
            "--set: objects.1.center.0=1e39: sphere center must be three finite numbers, got [1e39, 1.0, 0.0]",
        ),
        // A file the set names: the message is the set's, with no place in the file.
        (
            &["objects.1.material=m", "materials.m.texture={type=\"image\",path=\"nope.png\"}"],
            "--set: materials.m.texture={type=\"image\",path=\"nope.png\"}: cannot read texture nope.png: no such file",
        ),
        (
            &["render.spp=123456789012345678901234567890123456789012345"],
            "is beyond the 64-bit range of whole numbers",
        ),
        // Leading zeros: not a TOML number, so a string.
        (&["render.spp=010"], "expected a whole number (0 or more), got the string \"010\""),
        (
            &["render.spp=18446744073709551615"],
            "--set: render.spp=18446744073709551615: 18446744073709551615 is beyond the 64-bit range of whole numbers",
        ),
        (
            &["cameras.0.name=top"],
            "--set: cameras.0.name=top: the scene has no `cameras`; a set changes entries of a list but cannot add one (write [[cameras]] in the file)",
        ),
    ] {
        let err = set_err(&scene(), sets);
        assert!(err.starts_with("--set: ") && err.contains(words), "{sets:?}: {err}");
    }
}

#[test]
fn sets_that_add_keys_to_a_new_table_are_each_named() {
    // The first set adds `[fog]` at the end; the second goes under that
    // header, between the first one's header and its value.
    let text = scene();
    for (sets, named) in [
        (&["fog.density=-1", "fog.mode=\"exponential\""][..], "fog.density=-1"),
        (&["fog.mode=\"exponential\"", "fog.density=-1"], "fog.density=-1"),
        (&["fog.mode=\"mist\"", "fog.density=0.1"], "fog.mode=\"mist\""),
        (&["fog.density=0.1", "fog.mode=\"mist\""], "fog.mode=\"mist\""),
    ] {
        let err = set_err(&text, sets);
        assert!(err.starts_with(&format!("--set: {named}: ")), "{sets:?}: {err}");
    }
    // Three keys added to one new table; an error elsewhere keeps its line.
    let bad = text.replace("radius = 1", "radius = -1");
    let plain = with_sets(&bad, &[]).unwrap_err().to_string();
    let sets = ["fog.mode=\"exponential\"", "fog.density=0.1", "fog.color=[1, 1, 1]"];
    assert_eq!(set_err(&bad, &sets), plain);
}

#[test]
fn other_errors_keep_the_files_own_lines() {
    let bad = scene().replace("radius = 1", "radius = -1");
    let plain = with_sets(&bad, &[]).unwrap_err().to_string();
    assert!(plain.starts_with(&format!("{}: ", place(&bad, "-1"))), "{plain}");
    // A key added under [render] (a new line) and a table added at the end.
    let err = set_err(&bad, &["render.max_depth=3", "materials.green.color=[0, 1, 0]", "render.spp=2"]);
    assert_eq!(err, plain);
}

/// A problem with a whole table, told at its header, names the sets that
/// changed a value in that table (fuzz finding 10): the camera's up along
/// a view a set made vertical, a mesh that a set made of a plane.
#[test]
fn a_tables_problem_names_the_sets_in_that_table() {
    let text = scene();
    let camera = place(&text, "[camera]");
    let err = set_err(&text, &["camera.position=[0, 3, 1]", "camera.look_at=[0, 0, 1]"]);
    assert!(err.starts_with(&format!("{camera}: camera up [0, 1, 0] is zero or parallel")), "{err}");
    assert!(
        err.ends_with(
            " (this table holds values given by --set camera.position=[0, 3, 1] and --set camera.look_at=[0, 0, 1])"
        ),
        "{err}"
    );
    // A key the set adds to the table counts too; a set in another table does not.
    let err = set_err(&text, &["render.spp=4", "objects.0.type=mesh", "objects.0.normals=\"flat\""]);
    let plane = format!("{BASE}[[objects]]\n").len();
    let (line, col) = line_col(&text, plane - "[[objects]]\n".len());
    assert_eq!(
        err,
        format!(
            "s.toml:{line}:{col}: a mesh needs `path`, an OBJ file (relative to the scene file) \
             (this table holds values given by --set objects.0.type=mesh and --set objects.0.normals=\"flat\")"
        )
    );
    // A key set twice: the last set only.
    let err = set_err(
        &text,
        &["camera.position=[0, 9, 9]", "camera.look_at=[0, 0, 1]", "camera.position=[0, 3, 1]"],
    );
    assert!(
        err.ends_with(
            " (this table holds values given by --set camera.look_at=[0, 0, 1] and --set camera.position=[0, 3, 1])"
        ),
        "{err}"
    );
    // The same problem written in the file names no set.
    let bad = text
        .replace("position = [0, 2, 10]", "position = [0, 3, 1]")
        .replace("look_at = [0, 1, 0]", "look_at = [0, 0, 1]");
    let plain = set_err(&bad, &["render.spp=4"]);
    assert!(!plain.contains("--set"), "{plain}");
}

#[test]
fn warnings_keep_the_files_lines_or_name_the_set() {
    let eight = scene().replace("[0.8, 0.1, 0.1]", "[255, 0, 0]");
    let plain = with_sets(&eight, &[]).unwrap().warnings;
    assert!(
        plain[0].starts_with(&format!("{}: color [255, 0, 0] looks like 8-bit", place(&eight, "[255"))),
        "{plain:?}"
    );
    let l = with_sets(&eight, &["render.max_depth=2", "materials.blue.color=[0, 0, 255]"]).unwrap();
    assert_eq!(l.warnings.len(), 2, "{:?}", l.warnings);
    assert!(l.warnings.contains(&plain[0]), "{:?}", l.warnings);
    assert!(
        l.warnings
            .iter()
            .any(|w| w
                .starts_with("--set: materials.blue.color=[0, 0, 255]: color [0, 0, 255] looks like 8-bit")),
        "{:?}",
        l.warnings
    );
}

#[test]
fn an_obj_scene_refuses_sets() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("t.obj");
    fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let opts = LoadOptions { sets: vec!["render.spp=2".into()], ..LoadOptions::default() };
    let err = load_path(&obj, &opts).unwrap_err().to_string();
    assert!(err.starts_with("--set: render.spp=2:") && err.contains("OBJ"), "{err}");
}

#[test]
fn an_asset_error_names_where_the_file_or_a_set_names_the_asset() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("good.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    fs::write(dir.path().join("bad.obj"), "v 0 0 0\nf 1 2 3\n").unwrap();
    let load = |text: &str, sets: &[&str]| {
        let opts =
            LoadOptions { sets: sets.iter().map(|s| (*s).to_owned()).collect(), ..LoadOptions::default() };
        parse_scene_str_with(text, dir.path(), Path::new("s.toml"), &opts).unwrap_err().to_string()
    };
    // Named in the file, with lines added above it by sets: the file's line.
    let bad = format!("{}[[objects]]\ntype = \"mesh\"\npath = \"bad.obj\"\n", scene());
    let plain = load(&bad, &[]);
    assert!(plain.ends_with(&format!("(used at {})", place(&bad, "\"bad.obj"))), "{plain}");
    assert_eq!(load(&bad, &["render.max_depth=2", "fog.density=0.1", "fog.mode=\"exponential\""]), plain);
    // Named by a set: the set, then the asset's own place.
    let good = bad.replace("bad.obj", "good.obj");
    let err = load(&good, &["render.max_depth=2", "objects.2.path=\"bad.obj\""]);
    assert!(err.starts_with("--set: objects.2.path=\"bad.obj\": ") && err.contains("bad.obj:2"), "{err}");
    assert!(!err.contains("used at"), "{err}");
}

#[test]
fn a_fog_of_enabled_alone_is_the_switch_without_a_medium() {
    // `--set fog.enabled=false` on a scene without [fog]: no fog, no error.
    let off = with_sets(&scene(), &["fog.enabled=false"]).unwrap();
    assert!(!off.settings.fog && off.warnings.is_empty(), "{:?}", off.warnings);
    // An empty [fog] is linear fog without its `end`, as before.
    let empty = with_sets(&format!("{}[fog]\n", scene()), &[]).unwrap_err().to_string();
    assert!(empty.contains("linear fog needs `end`"), "{empty}");
    // On alone: the default fog `--fog` adds, with its warning.
    let text = format!("{}[fog]\nenabled = true\n", scene());
    let on = with_sets(&text, &[]).unwrap();
    assert!(on.settings.fog, "{text}");
    let fog = on.scene.fog.unwrap();
    assert!(matches!(fog.mode, prism_shade::FogMode::Linear { start: 0.0, .. }), "{fog:?}");
    assert_eq!(fog.color, prism_geometry::glam::Vec3::ONE);
    assert!(
        on.warnings
            .iter()
            .any(|w| w.contains("[fog] gives only `enabled`; using linear white fog from 0 to")),
        "{:?}",
        on.warnings
    );
}

#[test]
fn the_default_fog_scales_with_the_scene() {
    use prism_shade::FogMode;
    let end = |text: &str| match with_sets(text, &["fog.enabled=true"]).unwrap().scene.fog.map(|f| f.mode) {
        Some(FogMode::Linear { start: 0.0, end }) => end,
        other => panic!("{other:?}"),
    };
    // Bounded: 1.5 × the distance from the eye to the bounds' far corner,
    // here (±1, −1, −1) from (0, 1, 5): √41.
    let sphere = "camera.position = [0, 1, 5]\ncamera.look_at = [0, 0, 0]\n\
                  [[objects]]\ntype = \"sphere\"\nradius = 1\n";
    assert!((end(sphere) - 1.5 * 41f32.sqrt()).abs() < 1e-4, "{}", end(sphere));
    // Planes alone: 3 × the distance to the look-at point, so a scene ten
    // times larger gets fog ten times deeper (it was 100 for both).
    let floor = |k: f32| {
        format!(
            "camera.position = [0, {}, {}]\ncamera.look_at = [0, 0, 0]\n\
             [[objects]]\ntype = \"plane\"\nnormal = [0, 1, 0]\n",
            3.0 * k,
            4.0 * k
        )
    };
    assert_eq!(end(&floor(1.0)), 15.0);
    assert_eq!(end(&floor(10.0)), 150.0);
}

#[test]
fn sets_add_keys_to_tables_written_with_dotted_keys() {
    let text = "render.width = 64\nrender.height = 48\ncamera.position = [0, 1, 5]\ncamera.look_at = [0, 0, 0]\n\
                [[objects]]\ntype = \"sphere\"\nradius = 1\n";
    with_sets(text, &[]).unwrap();
    let l = with_sets(text, &["camera.fov=30"]).unwrap();
    assert_eq!(l.settings.camera.vfov_deg(), 30.0);
    let l = with_sets(text, &["render.spp=2", "camera.fov=30"]).unwrap();
    assert_eq!((l.settings.spp, l.settings.camera.vfov_deg()), (2, 30.0));
    let l = with_sets(text, &["camera.projection=\"orthographic\"", "render.spp=3"]).unwrap();
    assert_eq!(l.settings.spp, 3);
    assert_eq!(l.settings.camera.projection(), prism_shade::Projection::Orthographic);
    // Dotted keys under a header.
    let materials = format!("{text}material = \"red\"\n[materials]\nred.color = [1, 0, 0]\n");
    let l = with_sets(&materials, &["materials.red.specular=0.5"]).unwrap();
    assert_eq!(l.info.materials, ["red"]);
    // The set's key is the one added: an error in it names the flag.
    let err = set_err(&materials, &["materials.red.specular=-1"]);
    assert!(err.starts_with("--set: materials.red.specular=-1: "), "{err}");
    // An error elsewhere keeps the file's line.
    let bad = materials.replace("radius = 1", "radius = -1");
    let plain = with_sets(&bad, &[]).unwrap_err().to_string();
    assert_eq!(set_err(&bad, &["render.spp=2", "camera.fov=30", "materials.red.specular=0.5"]), plain);
}

#[test]
fn sets_add_keys_to_inline_tables_with_a_trailing_comma_or_line_breaks() {
    let base = format!(
        "{}[[objects]]\ntype = \"sphere\"\nradius = 1\nmaterial = \"red\"\n",
        BASE.replace("color = [0.8, 0.1, 0.1]\n", "")
    );
    for texture in [
        "texture = {\n  type = \"checker\",\n}\n",
        "texture = { type = \"checker\", }\n",
        "texture = { type = \"checker\" }\n",
        "texture = {\n  type = \"checker\" # a comment, with a comma\n}\n",
        "texture = {\n  type = \"checker\", # a comment\n}\n",
    ] {
        let text = base.replace("specular = 0.5\n", &format!("specular = 0.5\n{texture}"));
        with_sets(&text, &[]).unwrap();
        with_sets(&text, &["materials.red.texture.size=2"]).unwrap_or_else(|e| panic!("{texture}: {e}"));
        let err = set_err(&text, &["materials.red.texture.size=-2"]);
        assert!(
            err.starts_with("--set: materials.red.texture.size=-2: checker size must be"),
            "{texture}: {err}"
        );
    }
    // Each set is named for its own edit, not the one before it on the line.
    let text = format!(
        "objects = [\n  {{ type = \"plane\" }},\n  {{ type = \"sphere\",\n    radius = -3,\n  }},\n]\n{BASE}"
    );
    let plain = with_sets(&text, &[]).unwrap_err().to_string();
    assert!(plain.contains("sphere radius must be greater than 0, got -3"), "{plain}");
    with_sets(&text, &["objects.1.radius=2"]).unwrap();
    let err = set_err(&text, &["objects.1.radius=2", "objects.1.material=x"]);
    assert!(err.starts_with("--set: objects.1.material=x: unknown material `x`"), "{err}");
    let err = set_err(&text, &["objects.1.material=x", "objects.1.radius=2"]);
    assert!(err.starts_with("--set: objects.1.material=x: unknown material `x`"), "{err}");
}

/// A set that replaces a value written over several lines by one line
/// leaves every later place at the file's own line; so does one whose
/// value is shorter or longer than the file's on a line that goes on.
#[test]
fn places_after_a_replaced_value_keep_the_files_line_and_column() {
    let text = scene()
        .replace("position = [0, 2, 10]", "position = [\n  0,\n  2,\n  10,\n]")
        .replace("radius = 1", "radius = -1")
        .replace("color = [0.8, 0.1, 0.1]", "color = [255, 0, 0]");
    let plain = with_sets(&text, &[]).unwrap_err().to_string();
    assert!(plain.starts_with(&format!("{}: ", place(&text, "-1"))), "{plain}");
    for sets in [
        &["camera.position=[0, 2, 7]"][..],
        &["camera.position.2=7"],
        &["camera.position=[0, 2, 7]", "render.spp=3"],
    ] {
        assert_eq!(set_err(&text, sets), plain, "{sets:?}");
    }
    // A warning after it, too.
    let good = text.replace("radius = -1", "radius = 1");
    let warning = with_sets(&good, &[]).unwrap().warnings;
    assert_eq!(with_sets(&good, &["camera.position=[0, 2, 7]"]).unwrap().warnings, warning);
    // One line of inline tables: a problem after a set value on its line
    // is the file's, at its own column.
    let inline = "camera = { position = [0, 0, 5], look_at = [0, 0, 0], fov = 400 }\n";
    let plain = set_err(inline, &[]);
    assert!(plain.starts_with(&format!("{}: camera fov", place(inline, "400"))), "{plain}");
    for set in ["camera.position=[0,0,6]", "camera.position=[0, 0, 6.123456789]", "camera.position.2=6.5"] {
        assert_eq!(set_err(inline, &[set]), plain, "{set}");
    }
    let objects = "camera = { position = [0, 0, 5], look_at = [0, 0, 0] }\n\
                   objects = [ { type = \"sphere\", radius = 1 }, { type = \"sphere\", radius = -1 } ]\n";
    let plain = set_err(objects, &[]);
    assert!(plain.starts_with(&format!("{}: ", place(objects, "-1"))), "{plain}");
    assert_eq!(set_err(objects, &["objects.0.radius=2"]), plain);
    // The set's own value is still the set's.
    let err = set_err(objects, &["objects.1.radius=-3"]);
    assert!(
        err.starts_with("--set: objects.1.radius=-3: sphere radius must be greater than 0, got -3"),
        "{err}"
    );
}

/// A camera whose position a set moves onto its look-at point names the
/// set, as one whose look-at point a set moves does.
#[test]
fn a_camera_position_set_onto_its_look_at_names_the_set() {
    let text = scene();
    let err = set_err(&text, &["camera.position=[0, 1, 0]"]);
    assert!(
        err.starts_with(&format!(
            "{}: camera look_at [0, 1, 0] must differ from the camera position [0, 1, 0]",
            place(&text, "[camera]")
        )),
        "{err}"
    );
    assert!(err.ends_with(" (this table holds a value given by --set camera.position=[0, 1, 0])"), "{err}");
    let err = set_err(&text, &["camera.look_at=[0, 2, 10]"]);
    assert!(err.ends_with(" (this table holds a value given by --set camera.look_at=[0, 2, 10])"), "{err}");
}

/// A problem of a whole table that sets made names every set in it, not
/// the first alone.
#[test]
fn a_problem_of_a_table_sets_made_names_its_sets() {
    let text = scene();
    let sets = [
        "materials.glassy.specular=1",
        "materials.glassy.reflectivity=0.8",
        "materials.glassy.transparency=0.8",
    ];
    let err = set_err(&text, &sets);
    assert_eq!(
        err,
        "--set: reflectivity + transparency + transmission must not exceed 1, got 1.6 (in a table made by \
         --set materials.glassy.specular=1, --set materials.glassy.reflectivity=0.8 and \
         --set materials.glassy.transparency=0.8)"
    );
    // One set's value is still that set's problem.
    let err = set_err(&text, &["materials.glassy.specular=-1", "materials.glassy.reflectivity=0.5"]);
    assert!(err.starts_with("--set: materials.glassy.specular=-1: "), "{err}");
}

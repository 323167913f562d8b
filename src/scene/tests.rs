use super::*;
use std::fs;

fn shipped(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name).join(format!("{name}.toml"))
}

#[test]
fn loads_the_canonical_scenes() {
    for (name, tris) in [("cornell", 36), ("caustics", 3980), ("pointlight", 34), ("furnace", 12)] {
        let s = Scene::load(shipped(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(s.mesh.len(), tris, "{name}");
        assert_eq!(s.tri_material.len(), tris);
        assert_eq!(s.camera.width, 256);
    }
    let c = Scene::load(shipped("cornell")).unwrap();
    let light = c.material_names.iter().position(|n| n == "light").unwrap();
    assert_eq!(
        c.materials[light],
        Material::Emissive { kd: Vec3::splat(0.78), ke: Vec3::new(17.0, 12.0, 4.0) }
    );
    let caustics = Scene::load(shipped("caustics")).unwrap();
    assert!(caustics.materials.contains(&Material::Glass { ior: 1.5 }));
    assert!(caustics.materials.contains(&Material::Mirror { ks: Vec3::ONE }));
    let p = Scene::load(shipped("pointlight")).unwrap();
    assert_eq!(p.lights.len(), 1);
    assert!(p.materials.iter().all(|m| m.emission() == Vec3::ZERO));
}

/// Writes `files` into a temporary directory and loads `scene.toml` from it.
fn load_in_tmp(files: &[(&str, &str)]) -> Result<Scene, SceneError> {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        fs::write(dir.path().join(name), text).unwrap();
    }
    Scene::load(dir.path().join("scene.toml"))
}

const CAMERA: &str =
    "[camera]\neye = [0, 0, -2]\ntarget = [0, 0, 0]\nup = [0, 1, 0]\nvfov_deg = 40\nwidth = 8\nheight = 8\n";
const QUAD: &str = "mtllib q.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl w\nf 1 2 3 4\n";
const MTL: &str = "newmtl w\nKd 0.5 0.5 0.5\nillum 1\n";

fn scene_with_mesh() -> String {
    format!("{CAMERA}[[mesh]]\nobj = \"q.obj\"\n")
}

fn err(files: &[(&str, String)], expected: &str) -> String {
    let files: Vec<(&str, &str)> = files.iter().map(|(n, t)| (*n, t.as_str())).collect();
    match load_in_tmp(&files) {
        Ok(_) => panic!("expected an error containing `{expected}`"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn a_quad_is_split_as_in_the_conventions() {
    let s = load_in_tmp(&[("scene.toml", &scene_with_mesh()), ("q.obj", QUAD), ("q.mtl", MTL)]).unwrap();
    assert_eq!(s.mesh.indices, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(s.mesh.normal(0), Some(Vec3::Z));
    assert_eq!(s.materials, vec![Material::Diffuse { kd: Vec3::splat(0.5) }]);
}

#[test]
fn transforms_scale_translate_and_keep_winding() {
    let toml = format!("{CAMERA}[[mesh]]\nobj = \"q.obj\"\nscale = [-2, 2, 2]\ntranslate = [0, 0, 5]\n");
    let s = load_in_tmp(&[("scene.toml", &toml), ("q.obj", QUAD), ("q.mtl", MTL)]).unwrap();
    assert_eq!(s.mesh.positions[1], Vec3::new(-2.0, 0.0, 5.0));
    assert_eq!(s.mesh.normal(0), Some(Vec3::Z), "mirroring must not flip the front face");
}

#[test]
fn errors_name_the_file_and_line_or_field() {
    let m = scene_with_mesh();
    let cases: Vec<(Vec<(&str, String)>, &str)> = vec![
        (vec![("scene.toml", String::from(&m))], "q.obj: No such file"),
        (
            vec![("scene.toml", String::from(&m)), ("q.obj", String::from("v 0 0 0\nv 1 x 0\n"))],
            "q.obj:2: `x` is not a number",
        ),
        (
            vec![
                ("scene.toml", String::from(&m)),
                ("q.obj", String::from("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n")),
            ],
            "q.obj:2: vertex coordinate NaN",
        ),
        (
            vec![("scene.toml", String::from(&m)), ("q.obj", String::from("v 0 0 0\nv 1 0 0\nf 1 2 3\n"))],
            "q.obj:3: vertex index 3 out of range",
        ),
        (
            vec![("scene.toml", String::from(&m)), ("q.obj", String::from("v 0 0 0\nf 1 2\n"))],
            "q.obj:2: face needs 3 vertices",
        ),
        (vec![("scene.toml", String::from(&m)), ("q.obj", String::from("v 0 0 0\n"))], "no faces"),
        (vec![("scene.toml", String::from(&m)), ("q.obj", String::from(QUAD))], "q.obj:1: material library"),
        (
            vec![
                ("scene.toml", String::from(&m)),
                ("q.obj", String::from(QUAD)),
                ("q.mtl", String::from("newmtl w\nKd 0.5 oops 1\n")),
            ],
            "q.mtl:2: `Kd`",
        ),
        (
            vec![
                ("scene.toml", String::from(&m)),
                ("q.obj", String::from(QUAD)),
                ("q.mtl", String::from("newmtl other\nKd 0.5 0.5 0.5\n")),
            ],
            "q.obj:6: usemtl w",
        ),
        (
            vec![
                ("scene.toml", String::from(&format!("{m}[materials.w]\ntype = \"plastic\"\n"))),
                ("q.obj", String::from(QUAD)),
                ("q.mtl", String::from(MTL)),
            ],
            "line 11",
        ),
        (
            vec![
                ("scene.toml", String::from(&format!("{m}[materials.w]\nkd = [2, 0, 0]\n"))),
                ("q.obj", String::from(QUAD)),
                ("q.mtl", String::from(MTL)),
            ],
            "materials.w.kd",
        ),
        (
            vec![
                ("scene.toml", String::from(&format!("{m}[render]\nphotonz = 3\n"))),
                ("q.obj", String::from(QUAD)),
                ("q.mtl", String::from(MTL)),
            ],
            "unknown field `photonz`",
        ),
        (vec![("scene.toml", String::from(CAMERA))], "no [[mesh]]"),
        (
            vec![
                ("scene.toml", String::from(&m.replace("width = 8", "width = 1000000"))),
                ("q.obj", String::from(QUAD)),
                ("q.mtl", String::from(MTL)),
            ],
            "camera.width",
        ),
        (
            vec![
                ("scene.toml", String::from(&m.replace("vfov_deg = 40", "vfov_deg = nan"))),
                ("q.obj", String::from(QUAD)),
                ("q.mtl", String::from(MTL)),
            ],
            "camera.vfov_deg",
        ),
        (
            vec![
                ("scene.toml", String::from(&m.replace("target = [0, 0, 0]", "target = [0, 0, -2]"))),
                ("q.obj", String::from(QUAD)),
                ("q.mtl", String::from(MTL)),
            ],
            "degenerate view",
        ),
        (
            vec![
                (
                    "scene.toml",
                    format!("{m}[[light]]\ntype = \"point\"\nposition = [0, 0, 0]\nintensity = [1, -1, 1]\n"),
                ),
                ("q.obj", String::from(QUAD)),
                ("q.mtl", String::from(MTL)),
            ],
            "light[0].intensity",
        ),
        (
            vec![
                (
                    "scene.toml",
                    String::from(&format!("{m}[[light]]\ntype = \"laser\"\nposition = [0, 0, 0]\n")),
                ),
                ("q.obj", String::from(QUAD)),
                ("q.mtl", String::from(MTL)),
            ],
            "unknown variant `laser`",
        ),
        (vec![("scene.toml", String::from("[camera\n"))], "line 1"),
    ];
    for (files, expected) in cases {
        let e = err(&files, expected);
        assert!(e.contains(expected), "expected `{expected}` in: {e}");
        assert!(
            e.contains("scene.toml") || e.contains("q.obj") || e.contains("q.mtl"),
            "no file named in: {e}"
        );
    }
}

#[test]
fn mtl_illum_models_map_to_materials() {
    let mtl = "newmtl w\nKd 0.5 0.5 0.5\nKs 0.3 0.3 0.3\nNs 20\nillum 2\n";
    let s = load_in_tmp(&[("scene.toml", &scene_with_mesh()), ("q.obj", QUAD), ("q.mtl", mtl)]).unwrap();
    assert_eq!(s.materials[0], Material::Glossy { kd: Vec3::splat(0.5), ks: Vec3::splat(0.3), ns: 20.0 });
    for (illum, expected) in
        [("3", Material::Mirror { ks: Vec3::splat(0.3) }), ("7", Material::Glass { ior: 1.5 })]
    {
        let mtl = format!("newmtl w\nKs 0.3 0.3 0.3\nillum {illum}\n");
        let s = load_in_tmp(&[("scene.toml", &scene_with_mesh()), ("q.obj", QUAD), ("q.mtl", &mtl)]).unwrap();
        assert_eq!(s.materials[0], expected);
    }
}

#[test]
fn triangles_are_counted_per_material_even_when_two_are_equal() {
    let mut s = Scene::load(shipped("cornell")).unwrap();
    // Make the second material equal to the first: the counts must not merge.
    s.materials[1] = s.materials[0];
    let count = s.triangles_per_material();
    assert_eq!(count.len(), s.materials.len());
    assert_eq!(count.iter().sum::<usize>(), s.mesh.len());
    for (i, &n) in count.iter().enumerate() {
        assert_eq!(n, s.tri_material.iter().filter(|&&m| m as usize == i).count());
    }
}

/// Two named cameras: `front` keyed (frames 10 to 40, keys leaving fields out), `orbit` a
/// turntable at its own resolution.
const TWO_CAMERAS: &str = r#"
[[camera]]
name = "front"
eye = [0, 0, -2]
target = [0.5, 0.5, 0]
up = [0, 1, 0]
vfov_deg = 40
width = 8
height = 6

[[camera.key]]
frame = 10

[[camera.key]]
frame = 25
eye = [1, 0.5, -2]
vfov_deg = 30

[[camera.key]]
frame = 40
eye = [0.5, 1, -1.5]
up = [0.1, 1, 0]

[[camera]]
name = "orbit.v2"
eye = [0.5, 0.5, -3]
target = [0.5, 0.5, 0]
up = [0, 1, 0]
vfov_deg = 35
width = 4
height = 4
turntable = { frames = 120, degrees = 90.0 }
"#;

fn load_cameras(cameras: &str) -> Result<Scene, SceneError> {
    let toml = format!("{cameras}\n[[mesh]]\nobj = \"q.obj\"\n");
    load_in_tmp(&[("scene.toml", &toml), ("q.obj", QUAD), ("q.mtl", MTL)])
}

#[test]
fn a_single_camera_table_loads_as_before_named_camera() {
    let s = load_cameras(CAMERA).unwrap();
    let expected = Camera::look_at(Vec3::new(0.0, 0.0, -2.0), Vec3::ZERO, Vec3::Y, 40.0, 8, 8).unwrap();
    assert_eq!(s.camera, expected);
    assert_eq!(s.cameras.len(), 1);
    let c = &s.cameras[0];
    assert_eq!((c.name.as_str(), c.width, c.height, c.frames()), ("camera", 8, 8, None));
    assert_eq!(c.view(0), expected);
    assert_eq!(c.view(1234), expected);
    // The single table may be named and keyed too.
    let keyed = format!(
        "{CAMERA}name = \"hero\"\n[[camera.key]]\nframe = 0\n[[camera.key]]\nframe = 4\neye = [0, 1, -2]\n"
    );
    let s = load_cameras(&keyed).unwrap();
    assert_eq!((s.cameras[0].name.as_str(), s.cameras[0].frames()), ("hero", Some(0..=4)));
    assert_eq!(s.camera, expected, "the first frame is the camera's own view");
}

#[test]
fn a_camera_array_with_keys_and_a_turntable_loads() {
    let s = load_cameras(TWO_CAMERAS).unwrap();
    let names: Vec<&str> = s.cameras.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["front", "orbit.v2"]);
    let (front, orbit) = (&s.cameras[0], &s.cameras[1]);
    assert_eq!((front.width, front.height, front.frames()), (8, 6, Some(10..=40)));
    assert_eq!((orbit.width, orbit.height, orbit.frames()), (4, 4, Some(0..=119)));
    // `camera` is the first camera at its first frame, which is the table's own view.
    let own =
        Camera::look_at(Vec3::new(0.0, 0.0, -2.0), Vec3::new(0.5, 0.5, 0.0), Vec3::Y, 40.0, 8, 6).unwrap();
    assert_eq!(s.camera, own);
    assert_eq!(front.view(0), own, "frames before the first key are clamped to it");
    // Key 25 keeps the camera's target and up and sets its own eye and field of view.
    let at25 =
        Camera::look_at(Vec3::new(1.0, 0.5, -2.0), Vec3::new(0.5, 0.5, 0.0), Vec3::Y, 30.0, 8, 6).unwrap();
    assert_eq!(front.view(25), at25);
    // The turntable turns about the target (its default centre): 90 degrees over 120 frames,
    // so frame 60 is 45 degrees round.
    let half = orbit.view(60);
    let r = Vec3::new(0.5, 0.5, 0.0) - half.eye;
    assert!((r.length() - 3.0).abs() < 1e-5 && (r.x - r.z).abs() < 1e-5, "{half:?}");
}

#[test]
fn recentring_moves_every_camera() {
    let far = TWO_CAMERAS.replace("[0.5, 0.5, 0]", "[1000.5, 0.5, 0]").replace("eye = [0", "eye = [1000");
    let toml = format!("{far}\n[[mesh]]\nobj = \"q.obj\"\ntranslate = [1000, 0, 0]\n");
    let s = load_in_tmp(&[("scene.toml", &toml), ("q.obj", QUAD), ("q.mtl", MTL)]).unwrap();
    let moved = s.recentred().expect("the scene is far from the origin");
    let c = s.bounds().center();
    for (before, after) in s.cameras.iter().zip(&moved.cameras) {
        for frame in [0, 10, 17, 40, 60, 119] {
            let mut expected = before.view(frame);
            expected.eye -= c;
            assert_eq!(after.view(frame), expected, "{} frame {frame}", before.name);
        }
    }
    assert_eq!(moved.camera, moved.cameras[0].view(10));
}

#[test]
fn bad_cameras_are_refused_naming_the_field() {
    let front = TWO_CAMERAS;
    let second_named_front = front.replace("name = \"orbit.v2\"", "name = \"front\"");
    let cases: Vec<(String, &str)> = vec![
        (second_named_front, "field `camera[1].name`: duplicate camera name \"front\" (camera[0] has it too)"),
        (front.replace("name = \"orbit.v2\"\n", ""), "field `camera[1].name`: missing"),
        (front.replace("\"orbit.v2\"", "\"orbit v2\""), "field `camera[1].name`: \"orbit v2\" is not a camera name"),
        (front.replace("\"orbit.v2\"", "\"\""), "field `camera[1].name`: \"\" is not a camera name"),
        (front.replace("\"orbit.v2\"", "\"..\""), "field `camera[1].name`: \"..\" is not a camera name"),
        (front.replace("\"front\"", "\"a/b\""), "field `camera[0].name`: \"a/b\" is not a camera name"),
        (format!("{CAMERA}name = \"x y\"\n"), "field `camera.name`"),
        (front.replace("vfov_deg = 35", "vfov_deg = 180"), "field `camera[1].vfov_deg`: 180 is not in (0, 180)"),
        (front.replace("width = 4", "width = 0"), "field `camera[1].width`: 0 is not in 1..="),
        (
            front.replace("target = [0.5, 0.5, 0]\nup = [0, 1, 0]\nvfov_deg = 35", "target = [0.5, 0.5, -3]\nup = [0, 1, 0]\nvfov_deg = 35"),
            "field `camera[1]`: degenerate view",
        ),
        (
            format!("{CAMERA}[[camera.key]]\nframe = 3\n"),
            "field `camera.key`: 1 key given: an animation needs at least 2",
        ),
        (
            front.replace("frame = 40", "frame = 25"),
            "field `camera[0].key[2].frame`: frame 25 does not come after the previous key's frame 25",
        ),
        (
            front.replace("frame = 25", "frame = 5"),
            "field `camera[0].key[1].frame`: frame 5 does not come after the previous key's frame 10",
        ),
        (
            front.replace("frame = 40", "frame = 1000011"),
            "field `camera[0].key`: the animation spans 1000002 frames, more than 1000000",
        ),
        (
            front.replace("turntable = { frames = 120, degrees = 90.0 }", "turntable = { frames = 12 }\n[[camera.key]]\nframe = 0\n[[camera.key]]\nframe = 1"),
            "field `camera[1].turntable`: the camera has [[camera.key]]s as well",
        ),
        (front.replace("frames = 120", "frames = 0"), "field `camera[1].turntable.frames`: a turntable of 0 frames"),
        (front.replace("frames = 120", "frames = 1000001"), "field `camera[1].turntable.frames`: the animation spans 1000001 frames"),
        (front.replace("degrees = 90.0", "degrees = nan, axis = [0, 0, 0]"), "field `camera[1].turntable.degrees`: NaN is not finite"),
        (front.replace("degrees = 90.0", "axis = [0, 0, 0]"), "field `camera[1].turntable.axis`: the turntable's axis [0.0, 0.0, 0.0] is zero"),
        (front.replace("degrees = 90.0", "center = [inf, 0, 0]"), "field `camera[1].turntable.center`"),
        (front.replace("vfov_deg = 30", "vfov_deg = -1"), "field `camera[0].key[1].vfov_deg`: -1 is not in (0, 180)"),
        (front.replace("eye = [1, 0.5, -2]", "eye = [1, nan, -2]"), "field `camera[0].key[1].eye`"),
        // Eye and target cross at frame 1: the interpolated view there is degenerate.
        (
            format!("{CAMERA}[[camera.key]]\nframe = 0\neye = [-1, 0, 0]\ntarget = [1, 0, 0]\n[[camera.key]]\nframe = 2\neye = [1, 0, 0]\ntarget = [-1, 0, 0]\n"),
            "field `camera.key`: frame 1: the interpolated view is degenerate",
        ),
        (front.replace("frame = 25", "frame = 25\nroll = 3"), "unknown field `roll`"),
        (front.replace("frame = 25", "frame = -25"), "line 15, column 9: invalid value: integer `-25`, expected u32"),
        (front.replace("frames = 120", "frames = 120, spin = 2"), "unknown field `spin`"),
        (String::from("camera = []\n"), "field `camera`: an empty array"),
        (String::from("camera = 3\n"), "a [camera] table or [[camera]] tables"),
    ];
    for (toml, expected) in cases {
        let e = match load_cameras(&toml) {
            Ok(_) => panic!("expected an error containing `{expected}` from:\n{toml}"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains(expected), "expected `{expected}` in: {e}");
        assert!(e.contains("scene.toml: field `") || e.contains("scene.toml: line "), "{e}");
        assert!(!e.contains('\n'), "{e:?}");
    }
}

#[test]
fn unknown_camera_fields_keep_their_line() {
    // The hand-written `[camera]`-or-`[[camera]]` deserialiser keeps the table's own error.
    let e =
        load_cameras(&CAMERA.replace("width = 8", "width = 8\nfocal_length = 35")).unwrap_err().to_string();
    assert!(e.contains("line 7") && e.contains("unknown field `focal_length`"), "{e}");
    let e = load_cameras(&TWO_CAMERAS.replace("width = 4", "width = 4\nfocal_length = 35"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 31, column 1") && e.contains("unknown field `focal_length`"), "{e}");
}

#[test]
fn a_thin_lens_loads_focused_at_the_target_unless_told() {
    let lens = |s: &Scene| s.camera.lens;
    let s = load_cameras(&format!("{CAMERA}aperture_radius = 0.02\n")).unwrap();
    assert_eq!(lens(&s), Lens { aperture_radius: 0.02, focus_distance: 2.0 });
    let s = load_cameras(&format!("{CAMERA}aperture_radius = 0.02\nfocus_distance = 0.7\n")).unwrap();
    assert_eq!(lens(&s), Lens { aperture_radius: 0.02, focus_distance: 0.7 });
    // Aperture 0 is the pinhole camera the file would give without the fields.
    let s = load_cameras(&format!("{CAMERA}aperture_radius = 0\nfocus_distance = 3\n")).unwrap();
    assert_eq!(s.camera, load_cameras(CAMERA).unwrap().camera);
    // A key without a focus distance focuses at its own target, unless the camera gives one;
    // it keeps the camera's aperture unless it sets its own.
    let keys = "[[camera.key]]\nframe = 0\n[[camera.key]]\nframe = 4\neye = [0, 0, -3]\n[[camera.key]]\nframe = 8\naperture_radius = 0.05\nfocus_distance = 1.5\n";
    let s = load_cameras(&format!("{CAMERA}aperture_radius = 0.01\n{keys}")).unwrap();
    let lens_at = |f: u32| s.cameras[0].view(f).lens;
    assert_eq!(lens_at(4), Lens { aperture_radius: 0.01, focus_distance: 3.0 });
    assert_eq!(lens_at(8), Lens { aperture_radius: 0.05, focus_distance: 1.5 });
    let s = load_cameras(&format!("{CAMERA}aperture_radius = 0.01\nfocus_distance = 0.5\n{keys}")).unwrap();
    assert_eq!(s.cameras[0].view(4).lens, Lens { aperture_radius: 0.01, focus_distance: 0.5 });
}

#[test]
fn bad_lenses_are_refused_naming_the_field() {
    let cases: Vec<(String, &str)> = vec![
        (
            format!("{CAMERA}aperture_radius = -0.01\n"),
            "field `camera.aperture_radius`: -0.01 is not a radius",
        ),
        (format!("{CAMERA}aperture_radius = nan\n"), "field `camera.aperture_radius`: NaN is not a radius"),
        (
            format!("{CAMERA}aperture_radius = 0.1\nfocus_distance = 0\n"),
            "field `camera.focus_distance`: 0 is not a distance",
        ),
        (
            format!("{CAMERA}aperture_radius = 0.1\nfocus_distance = -2\n"),
            "field `camera.focus_distance`: -2 is not a distance",
        ),
        (format!("{CAMERA}focus_distance = inf\n"), "field `camera.focus_distance`: inf is not a distance"),
        (
            TWO_CAMERAS.replace("vfov_deg = 30", "vfov_deg = 30\naperture_radius = -1"),
            "field `camera[0].key[1].aperture_radius`: -1 is not a radius",
        ),
        (
            TWO_CAMERAS.replace("vfov_deg = 30", "vfov_deg = 30\nfocus_distance = 0"),
            "field `camera[0].key[1].focus_distance`: 0 is not a distance",
        ),
        (format!("{CAMERA}aperture = 0.1\n"), "unknown field `aperture`"),
    ];
    for (toml, expected) in cases {
        let e = match load_cameras(&toml) {
            Ok(_) => panic!("expected an error containing `{expected}` from:\n{toml}"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains(expected), "expected `{expected}` in: {e}");
        assert!(!e.contains('\n'), "{e:?}");
    }
}

/// A quad in the z = 0 plane with a normal per vertex: three +Z and one without (`vn` 0 0 0).
const QUAD_VN: &str =
    "mtllib q.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 0\nusemtl w\nf 1//1 2//1 3//1 4//2\n";

#[test]
fn rotations_and_matrices_place_the_mesh_and_its_normals() {
    let load = |transform: &str| {
        let toml = format!("{CAMERA}[[mesh]]\nobj = \"q.obj\"\n{transform}\n");
        load_in_tmp(&[("scene.toml", &toml), ("q.obj", QUAD_VN), ("q.mtl", MTL)])
    };
    // A quarter turn about +Y takes the quad's +Z normal to +X, and (1, 0, 0) to (0, 0, -1).
    let s = load("rotate = { axis = [0, 1, 0], degrees = 90 }\ntranslate = [0, 0, 1]").unwrap();
    let (p, n) = (&s.mesh.positions, &s.attributes.normals);
    assert!((p[1] - Vec3::new(0.0, 0.0, 0.0)).length() < 1e-6, "{p:?}");
    assert!((s.mesh.normal(0).unwrap() - Vec3::X).length() < 1e-6);
    assert!((n[0] - Vec3::X).length() < 1e-6, "{n:?}");
    assert!(n.contains(&Vec3::ZERO), "a vertex without a normal stays without one");
    // A mirroring matrix keeps the front face on the normals' side.
    let s = load("matrix = [-1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]").unwrap();
    assert_eq!(s.mesh.normal(0), Some(Vec3::Z));
    assert_eq!(s.mesh.positions[1], Vec3::new(-1.0, 0.0, 0.0));
    let e = load("rotate = { axis = [0, 0, 0], degrees = 90 }").unwrap_err().to_string();
    assert!(e.contains("scene.toml: field `mesh[0].rotate.axis`: is zero"), "{e}");
    let e = load("rotate = { axis = [0, 1, 0], angle = 90 }").unwrap_err().to_string();
    assert!(e.contains("line 10, column 30: unknown field `angle`"), "{e}");
}

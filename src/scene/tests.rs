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

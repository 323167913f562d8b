//! Which images a batch renders and where each goes: the cameras and frames asked for, and
//! output names made from a pattern (`out/{camera}_{frame:04}.exr`).

use crate::scene::{Camera, Scene};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// One image of a batch: camera `camera` (an index into the scene's cameras) at `frame`.
#[derive(Clone, Debug, PartialEq)]
pub struct Job {
    pub camera: usize,
    pub frame: u32,
    pub output: PathBuf,
    pub png: Option<PathBuf>,
}

/// The image formats an output may have, from its extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Float RGB OpenEXR, with the record of how it was made.
    Exr,
    /// 8-bit sRGB PNG.
    Png,
}

impl Format {
    /// The format `path`'s extension names (case-insensitive), or a sentence saying it names
    /// none this program writes.
    pub fn of(path: &Path) -> Result<Format, String> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("exr") => Ok(Format::Exr),
            Some("png") => Ok(Format::Png),
            Some(other) => Err(format!(
                "{}: `.{other}` is not an image format photonmap writes (.exr or .png)",
                path.display()
            )),
            None => Err(format!("{}: no extension to tell the image format (.exr or .png)", path.display())),
        }
    }
}

/// The `-o` a render without one gets: the scene file's name in the working directory, with
/// `{camera}` and `{frame:04}` where `selection` asks for more than one camera or frame.
pub fn default_output(scene: &Scene, selection: Selection<'_>) -> Result<PathBuf, String> {
    let stem = scene.path.file_stem().map_or("render".into(), |s| s.to_string_lossy().into_owned());
    let probe = plan(scene, selection, Path::new("{camera}/{frame}.exr"), None)?;
    let cameras = probe.iter().map(|j| j.camera).collect::<std::collections::HashSet<_>>().len();
    let many_frames = probe.iter().any(|j| probe.iter().any(|k| k.camera == j.camera && k.frame != j.frame));
    let mut name = stem.replace('{', "(").replace('}', ")");
    if cameras > 1 {
        name += "_{camera}";
    }
    if many_frames {
        name += "_{frame:04}";
    }
    Ok(PathBuf::from(name + ".exr"))
}

/// What the command line asks for.
#[derive(Clone, Copy, Debug, Default)]
pub struct Selection<'a> {
    /// Camera names (`--cameras`); `None`: every camera.
    pub cameras: Option<&'a [String]>,
    /// Frames (`--frames`); `None`: each camera's own (an animation's range, frame 0 for a
    /// still camera).
    pub frames: Option<&'a [u32]>,
}

/// The images `selection` asks of `scene`, cameras in the scene file's order (or the order
/// named), each camera's frames in order, with their output names from the patterns. Refused
/// with one sentence: an unknown camera, a frame outside a camera's animation, a pattern that
/// gives two images the same name (or an image and a PNG), a bad placeholder.
pub fn plan(
    scene: &Scene,
    selection: Selection<'_>,
    output: &Path,
    png: Option<&Path>,
) -> Result<Vec<Job>, String> {
    let cameras: Vec<usize> = match selection.cameras {
        None => (0..scene.cameras.len()).collect(),
        Some(names) => names.iter().map(|n| camera_index(scene, n)).collect::<Result<_, _>>()?,
    };
    let mut jobs = Vec::new();
    for &c in &cameras {
        let cam = &scene.cameras[c];
        let frames: Vec<u32> = match (selection.frames, cam.frames()) {
            (None, Some(range)) => range.collect(),
            (None, None) => vec![0],
            (Some(list), range) => {
                let outside =
                    range.as_ref().and_then(|r| list.iter().find(|f| !r.contains(f)).map(|&f| (r, f)));
                if let Some((range, bad)) = outside {
                    return Err(format!(
                        "--frames: frame {bad} is outside camera {}'s animation (frames {}-{})",
                        cam.name,
                        range.start(),
                        range.end()
                    ));
                }
                list.to_vec()
            }
        };
        for frame in frames {
            let output = expand(output, &cam.name, frame)?;
            let png = png.map(|p| expand(p, &cam.name, frame)).transpose()?;
            jobs.push(Job { camera: c, frame, output, png });
        }
    }
    for job in &jobs {
        Format::of(&job.output)?;
        if let Some(png) = &job.png {
            if Format::of(png)? != Format::Png {
                return Err(format!("{}: --png names a PNG file (.png)", png.display()));
            }
        }
    }
    check_distinct(&jobs)?;
    Ok(jobs)
}

/// Every view of every camera of `scene` (each animation frame of each camera, one view of a
/// still camera), at the resolution each image is rendered at: what the photon stages serve,
/// the same whatever images a command selects, so that an image does not depend on which
/// others are rendered with it (a resumed batch gives the images the whole one would).
pub fn all_views(scene: &Scene, size: impl Fn(usize) -> (u32, u32)) -> Vec<Camera> {
    let mut views = Vec::new();
    for (c, cam) in scene.cameras.iter().enumerate() {
        let (w, h) = size(c);
        match cam.frames() {
            Some(range) => views.extend(range.map(|f| cam.view(f).with_resolution(w, h))),
            None => views.push(cam.view(0).with_resolution(w, h)),
        }
    }
    views
}

/// Where `job`'s view is in [`all_views`]'s list.
pub fn view_index(scene: &Scene, job: &Job) -> usize {
    let before: usize = scene.cameras[..job.camera]
        .iter()
        .map(|c| c.frames().map_or(1, |r| (r.end() - r.start() + 1) as usize))
        .sum();
    let own = scene.cameras[job.camera].frames().map_or(0, |r| (job.frame - r.start()) as usize);
    before + own
}

fn camera_index(scene: &Scene, name: &str) -> Result<usize, String> {
    scene.cameras.iter().position(|c| c.name == name).ok_or_else(|| {
        let names: Vec<&str> = scene.cameras.iter().map(|c| c.name.as_str()).collect();
        format!("--cameras: no camera named {name:?} (the scene has {})", names.join(", "))
    })
}

/// `pattern` with `{camera}`, `{frame}` and `{frame:0N}` (zero-padded to N digits) replaced.
pub fn expand(pattern: &Path, camera: &str, frame: u32) -> Result<PathBuf, String> {
    let text = pattern.to_str().ok_or_else(|| format!("{}: not valid UTF-8", pattern.display()))?;
    if !text.contains('{') && !text.contains('}') {
        return Ok(pattern.to_path_buf());
    }
    let mut out = String::new();
    let mut rest = text;
    while let Some(open) = rest.find(['{', '}']) {
        out.push_str(&rest[..open]);
        let bad =
            |what: &str| format!("{text}: {what} (placeholders are {{camera}}, {{frame}} and {{frame:04}})");
        if rest.as_bytes()[open] == b'}' {
            return Err(bad("a '}' without its '{'"));
        }
        let close = rest[open..].find('}').ok_or_else(|| bad("a '{' without its '}'"))? + open;
        let name = &rest[open + 1..close];
        match name {
            "camera" => out.push_str(camera),
            "frame" => out.push_str(&frame.to_string()),
            _ => match name.strip_prefix("frame:0").map(str::parse::<usize>) {
                Some(Ok(width)) if (1..=9).contains(&width) => out.push_str(&format!("{frame:0width$}")),
                _ => return Err(bad(&format!("unknown placeholder {{{name}}}"))),
            },
        }
        rest = &rest[close + 1..];
    }
    out.push_str(rest);
    Ok(PathBuf::from(out))
}

/// No two files of the batch (images and PNGs) share a name.
fn check_distinct(jobs: &[Job]) -> Result<(), String> {
    let mut seen: HashMap<&Path, usize> = HashMap::new();
    for (i, job) in jobs.iter().enumerate() {
        for path in std::iter::once(&job.output).chain(&job.png) {
            if let Some(&first) = seen.get(path.as_path()) {
                let hint = if first == i {
                    "the image and its PNG"
                } else if jobs[first].camera != job.camera {
                    "two cameras' images: put {camera} in the name"
                } else {
                    "two frames' images: put {frame} or {frame:04} in the name"
                };
                return Err(format!("{}: names {hint}", path.display()));
            }
            seen.insert(path, i);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_expand_and_bad_ones_are_refused() {
        let e = |p: &str| expand(Path::new(p), "front", 7).map(|p| p.display().to_string());
        assert_eq!(e("out.exr").unwrap(), "out.exr");
        assert_eq!(e("out/{camera}_{frame}.exr").unwrap(), "out/front_7.exr");
        assert_eq!(e("{camera}/{frame:04}.exr").unwrap(), "front/0007.exr");
        assert_eq!(e("f{frame:02}{frame:03}").unwrap(), "f07007");
        for bad in ["{cam}.exr", "{frame:4}.exr", "{frame.exr", "frame}.exr", "{frame:00}.exr", "{}.exr"] {
            let err = e(bad).unwrap_err();
            assert!(err.contains(bad) && err.contains("placeholders are"), "{bad}: {err}");
        }
    }

    #[test]
    fn colliding_names_are_refused_with_the_fix() {
        let job = |camera, frame, output: &str, png: Option<&str>| Job {
            camera,
            frame,
            output: output.into(),
            png: png.map(Into::into),
        };
        assert!(check_distinct(&[job(0, 0, "a.exr", Some("a.png")), job(0, 1, "b.exr", None)]).is_ok());
        let frames = check_distinct(&[job(0, 0, "a.exr", None), job(0, 1, "a.exr", None)]).unwrap_err();
        assert!(frames.contains("{frame"), "{frames}");
        let cams = check_distinct(&[job(0, 0, "a.exr", None), job(1, 0, "a.exr", None)]).unwrap_err();
        assert!(cams.contains("{camera}"), "{cams}");
        let own = check_distinct(&[job(0, 0, "a.exr", Some("a.exr"))]).unwrap_err();
        assert!(own.contains("PNG"), "{own}");
    }
}

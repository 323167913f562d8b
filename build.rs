//! Build script: with the `embree` feature, finds the installed Embree (4 preferred, else 3) and
//! runs bindgen on *its* headers, so the bindings always match the library that is linked.
//!
//! Discovery order: `EMBREE_DIR` (`include/`, and `lib/`, `lib64/` or `lib/<multiarch>/`), then
//! pkg-config (`embree4`, then `embree3`), then the system include paths. The version is read
//! from `RTC_VERSION_MAJOR/MINOR/PATCH` in `rtcore_config.h`; the script emits
//! `cfg(embree4)` or `cfg(embree3)` and `PHOTONMAP_EMBREE_VERSION`, and links `embree4`/`embree3`.
//!
//! When linking, the library's version (from its file name or the version string compiled into
//! it) must equal the headers': a mismatch is a build error naming both.
//!
//! `PHOTONMAP_EMBREE_CHECK_ONLY=1` generates the bindings but emits no link directives: it lets
//! `scripts/check-embree4.sh` type-check against headers whose library is not installed.

fn main() {
    println!("cargo::rustc-check-cfg=cfg(embree3)");
    println!("cargo::rustc-check-cfg=cfg(embree4)");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=EMBREE_DIR");
    println!("cargo:rerun-if-env-changed=PHOTONMAP_EMBREE_CHECK_ONLY");
    println!("cargo:rerun-if-env-changed=PKG_CONFIG_PATH");
    #[cfg(feature = "embree")]
    embree::generate();
}

#[cfg(feature = "embree")]
mod embree {
    use std::env;
    use std::path::{Path, PathBuf};
    use std::process::Command;

    const NOT_FOUND: &str = "Embree not found: install it with `apt-get install libembree-dev` \
        (Debian/Ubuntu), set EMBREE_DIR, or build without it: cargo build --no-default-features";

    /// An Embree installation: `include` holds `embree<major>/rtcore.h`.
    struct Install {
        major: u32,
        include: PathBuf,
        lib_dirs: Vec<PathBuf>,
        /// Whether the library directories need an rpath (not on the default linker path).
        rpath: bool,
        found_by: String,
    }

    /// `include/embree4/rtcore.h` if present, else `include/embree3/rtcore.h`.
    fn headers_in(include: &Path) -> Option<u32> {
        [4, 3].into_iter().find(|m| include.join(format!("embree{m}/rtcore.h")).is_file())
    }

    fn from_embree_dir(dir: &Path) -> Install {
        let include = dir.join("include");
        let major = headers_in(&include).unwrap_or_else(|| {
            panic!(
                "EMBREE_DIR={}: no include/embree4/rtcore.h or include/embree3/rtcore.h there. {NOT_FOUND}",
                dir.display()
            )
        });
        // Debian puts the library in lib/<multiarch>/, other layouts in lib/ or lib64/.
        let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
        let os = env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
        let abi = env::var("CARGO_CFG_TARGET_ENV").unwrap_or_default();
        let multiarch = format!("lib/{arch}-{os}-{abi}");
        let lib_dirs = ["lib", "lib64", multiarch.as_str()]
            .iter()
            .map(|d| dir.join(d))
            .filter(|d| {
                d.join(format!("libembree{major}.so")).exists()
                    || d.join(format!("embree{major}.lib")).exists()
            })
            .collect();
        Install { major, include, lib_dirs, rpath: true, found_by: format!("EMBREE_DIR={}", dir.display()) }
    }

    fn pkg_config(name: &str, flag: &str) -> Option<Vec<PathBuf>> {
        let out = Command::new("pkg-config").args([flag, name]).output().ok()?;
        if !out.status.success() {
            return None;
        }
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        let prefix = &flag[flag.len() - 2..]; // "-I" or "-L"
        Some(text.split_whitespace().filter_map(|t| t.strip_prefix(prefix)).map(PathBuf::from).collect())
    }

    fn from_pkg_config() -> Option<Install> {
        for major in [4, 3] {
            let name = format!("embree{major}");
            let Some(includes) = pkg_config(&name, "--cflags-only-I") else { continue };
            let lib_dirs = pkg_config(&name, "--libs-only-L").unwrap_or_default();
            let mut candidates = includes.clone();
            // Some .pc files point at include/embreeN itself.
            candidates.extend(includes.iter().filter_map(|p| p.parent().map(Path::to_path_buf)));
            candidates.extend(["/usr/include", "/usr/local/include"].map(PathBuf::from));
            if let Some(include) = candidates.into_iter().find(|i| headers_in(i) == Some(major)) {
                let found_by = format!("pkg-config {name}");
                return Some(Install { major, include, rpath: !lib_dirs.is_empty(), lib_dirs, found_by });
            }
        }
        None
    }

    fn from_system() -> Option<Install> {
        let dirs = ["/usr/include", "/usr/local/include"];
        for major in [4, 3] {
            for dir in dirs {
                let include = PathBuf::from(dir);
                if include.join(format!("embree{major}/rtcore.h")).is_file() {
                    let lib_dirs = match dir {
                        "/usr/local/include" => vec![PathBuf::from("/usr/local/lib")],
                        _ => Vec::new(),
                    };
                    let found_by = format!("system headers in {dir}");
                    return Some(Install { major, include, lib_dirs, rpath: false, found_by });
                }
            }
        }
        None
    }

    /// `(major, minor, patch)` from `RTC_VERSION_*` in `rtcore_config.h`.
    fn read_version(config: &Path) -> (u32, u32, u32) {
        let text = std::fs::read_to_string(config)
            .unwrap_or_else(|e| panic!("cannot read {}: {e}", config.display()));
        let field = |name: &str| -> u32 {
            text.lines()
                .filter_map(|l| l.trim().strip_prefix("#define "))
                .filter_map(|l| l.trim().strip_prefix(name))
                .find_map(|rest| rest.trim().parse().ok())
                .unwrap_or_else(|| panic!("{}: no `#define {name} <number>`", config.display()))
        };
        (field("RTC_VERSION_MAJOR"), field("RTC_VERSION_MINOR"), field("RTC_VERSION_PATCH"))
    }

    /// The library `-lembree{major}` resolves to: `libembree{major}.so` in `lib_dirs`, or, for
    /// a system install (no lib dirs), in the default library directories.
    fn library_file(lib_dirs: &[PathBuf], major: u32) -> Option<PathBuf> {
        let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
        let os = env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
        let abi = env::var("CARGO_CFG_TARGET_ENV").unwrap_or_default();
        let defaults = [format!("/usr/lib/{arch}-{os}-{abi}"), "/usr/lib64".into(), "/usr/lib".into()]
            .map(PathBuf::from);
        let dirs = if lib_dirs.is_empty() { &defaults[..] } else { lib_dirs };
        dirs.iter().map(|d| d.join(format!("libembree{major}.so"))).find(|f| f.exists())
    }

    /// The Embree version of the shared library `file` (a symlink is followed): from the real
    /// file's name (`libembree4.so.4.3.3`, as Debian and Intel's releases name it), else from
    /// the `RTC_VERSION_STRING` literal (`"4.3.3"`, NUL-terminated) compiled into it, which is
    /// also there when the file was renamed (as Python wheels do: `libembree4-92ec4c98.so.4`).
    fn library_version(file: &Path, major: u32) -> Result<String, String> {
        let real = std::fs::canonicalize(file).map_err(|e| format!("{}: {e}", file.display()))?;
        let is_version = |s: &str| {
            let parts: Vec<&str> = s.split('.').collect();
            parts.len() == 3
                && parts[0] == major.to_string()
                && parts.iter().all(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()))
        };
        let name = real.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        if let Some(v) = name.strip_prefix(&format!("libembree{major}.so.")).filter(|v| is_version(v)) {
            return Ok(v.to_string());
        }
        let bytes = std::fs::read(&real).map_err(|e| format!("{}: {e}", real.display()))?;
        let mut found: Vec<&str> = bytes
            .split(|&b| b == 0)
            .filter(|s| s.len() <= 16)
            .filter_map(|s| std::str::from_utf8(s).ok())
            .filter(|s| is_version(s))
            .collect();
        found.sort_unstable();
        found.dedup();
        match found[..] {
            [v] => Ok(v.to_string()),
            [] => Err(format!("{}: no {major}.x.y version string in the library", real.display())),
            _ => Err(format!(
                "{}: several version strings in the library: {}",
                real.display(),
                found.join(", ")
            )),
        }
    }

    /// Fails the build when the library that will be linked is another Embree version than
    /// the headers the bindings come from: the structs passed to Embree (rays, hits, query
    /// arguments) differ between 4.x releases, and a mismatch overruns them at run time.
    fn check_library_version(install: &Install, headers: &str) {
        let major = install.major;
        let Some(file) = library_file(&install.lib_dirs, major) else {
            println!(
                "cargo:warning=Embree {headers}: libembree{major}.so not found, its version is not checked"
            );
            return;
        };
        println!("cargo:rerun-if-changed={}", file.display());
        match library_version(&file, major) {
            Ok(v) if v == headers => {}
            Ok(v) => panic!(
                "Embree version mismatch ({}): the headers are {headers} but the library {} is {v}; \
                 use the headers of the library's release",
                install.found_by,
                file.display()
            ),
            Err(e) if env::var_os("EMBREE_DIR").is_some_and(|d| !d.is_empty()) => panic!(
                "{}: cannot tell the version of the Embree library (headers: {headers}): {e}",
                install.found_by
            ),
            Err(e) => println!("cargo:warning=Embree {headers}: library version not checked: {e}"),
        }
    }

    pub fn generate() {
        let install = match env::var_os("EMBREE_DIR").filter(|d| !d.is_empty()) {
            Some(dir) => from_embree_dir(Path::new(&dir)),
            None => from_pkg_config().or_else(from_system).unwrap_or_else(|| panic!("{NOT_FOUND}")),
        };
        let major = install.major;
        let header_dir = install.include.join(format!("embree{major}"));
        let (maj, min, patch) = read_version(&header_dir.join("rtcore_config.h"));
        assert_eq!(
            maj, major,
            "{}: embree{major}/rtcore_config.h says version {maj}.{min}.{patch}",
            install.found_by
        );
        println!("cargo:rerun-if-changed={}", header_dir.display());
        println!("cargo:rustc-cfg=embree{major}");
        println!("cargo:rustc-env=PHOTONMAP_EMBREE_VERSION={maj}.{min}.{patch}");

        let check_only = env::var("PHOTONMAP_EMBREE_CHECK_ONLY").is_ok_and(|v| v == "1");
        if !check_only {
            if install.rpath && install.lib_dirs.is_empty() && env::var_os("EMBREE_DIR").is_some() {
                panic!(
                    "{}: no libembree{major}.so in lib/, lib64/ or lib/<multiarch>/ \
                     (set PHOTONMAP_EMBREE_CHECK_ONLY=1 to only type-check against the headers)",
                    install.found_by
                );
            }
            for dir in &install.lib_dirs {
                println!("cargo:rustc-link-search=native={}", dir.display());
                if install.rpath {
                    println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display());
                }
            }
            println!("cargo:rustc-link-lib=dylib=embree{major}");
            check_library_version(&install, &format!("{maj}.{min}.{patch}"));
        }

        let bindings = bindgen::Builder::default()
            .header_contents("photonmap_embree.h", &format!("#include <embree{major}/rtcore.h>\n"))
            .clang_arg(format!("-I{}", install.include.display()))
            .allowlist_function("rtc.*")
            .allowlist_type("RTC.*")
            .allowlist_var("RTC.*")
            .prepend_enum_name(false)
            .derive_default(true)
            .generate_comments(false)
            .generate()
            .unwrap_or_else(|e| panic!("bindgen failed on {}: {e}", header_dir.display()));
        let out = PathBuf::from(env::var("OUT_DIR").expect("OUT_DIR")).join("embree_bindings.rs");
        bindings.write_to_file(&out).unwrap_or_else(|e| panic!("cannot write {}: {e}", out.display()));
    }
}

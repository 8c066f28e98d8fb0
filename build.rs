//! Checks that the system SUNDIALS 6 (Debian's `libsundials-dev`), KLU and libclang are
//! present before anything links against them, and stops with one actionable line if not.
//! (Without this, `sundials-sys` silently builds its bundled SUNDIALS 7, another API.)

use std::path::Path;

const APT: &str = "sudo apt-get install -y --no-install-recommends libsundials-dev libsuitesparse-dev libclang-dev (or run `make deps`)";

fn fail(what: &str) -> ! {
    eprintln!("error: {what}; install it with: {APT}");
    println!("cargo::error={what}; install it with: {APT}");
    std::process::exit(1);
}

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-env-changed=SUNDIALS_INCLUDE_DIR");
    let inc = std::env::var("SUNDIALS_INCLUDE_DIR").unwrap_or_else(|_| "/usr/include".into());
    let config = Path::new(&inc).join("sundials/sundials_config.h");
    let text = std::fs::read_to_string(&config).unwrap_or_else(|_| {
        fail(&format!(
            "SUNDIALS headers not found ({} is missing)",
            config.display()
        ))
    });
    let version = text
        .lines()
        .find_map(|l| l.strip_prefix("#define SUNDIALS_VERSION \""))
        .and_then(|v| v.split('"').next())
        .unwrap_or("unknown")
        .to_string();
    if !version.starts_with("6.") {
        fail(&format!(
            "cellsim needs SUNDIALS 6.x, found {version} in {}",
            config.display()
        ));
    }
    for h in [
        "idas/idas.h",
        "sunlinsol/sunlinsol_klu.h",
        "nvector/nvector_serial.h",
    ] {
        if !Path::new(&inc).join(h).exists() {
            fail(&format!("SUNDIALS header {h} not found under {inc}"));
        }
    }
    let klu = ["/usr/include/suitesparse/klu.h", "/usr/include/klu.h"];
    if std::env::var("SUITESPARSE_INCLUDE_DIR").is_err()
        && !klu.iter().any(|p| Path::new(p).exists())
    {
        fail("KLU header klu.h not found (SuiteSparse)");
    }
    let has_libclang = std::env::var("LIBCLANG_PATH").is_ok()
        || glob_any(
            &[
                "/usr/lib/x86_64-linux-gnu",
                "/usr/lib/aarch64-linux-gnu",
                "/usr/lib",
            ],
            "libclang",
        )
        || std::fs::read_dir("/usr/lib")
            .map(|d| {
                d.flatten().any(|e| {
                    e.file_name().to_string_lossy().starts_with("llvm-")
                        && glob_any(&[&format!("{}/lib", e.path().display())], "libclang")
                })
            })
            .unwrap_or(false);
    if !has_libclang {
        fail("libclang (needed by bindgen to read the SUNDIALS headers) not found");
    }
    println!("cargo::rustc-env=CELLSIM_SUNDIALS_VERSION={version}");
}

fn glob_any(dirs: &[&str], prefix: &str) -> bool {
    dirs.iter().any(|d| {
        std::fs::read_dir(d)
            .map(|it| {
                it.flatten().any(|e| {
                    let n = e.file_name().to_string_lossy().into_owned();
                    n.starts_with(prefix) && n.contains(".so")
                })
            })
            .unwrap_or(false)
    })
}

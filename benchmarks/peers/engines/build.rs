//! Compiles src/jolt_settings.cpp (what JoltC's C API lacks: the PhysicsSettings, gravity, a
//! body's inverse mass) against the Jolt headers that joltc-sys vendors, with the definitions and
//! instruction-set flags of joltc-sys's CMake build of Jolt 5.0.0 in its Release configuration
//! (JoltPhysics/Build/CMakeLists.txt defaults: debug renderer and profiler on in Release,
//! SSE4.1/4.2, AVX, AVX2, LZCNT, TZCNT, F16C, FMADD), so that the PhysicsSystem seen from here has
//! the layout of the one built there. main.rs checks the defaults it reads back.
use std::path::PathBuf;
use std::process::Command;

fn joltc_sys_dir() -> PathBuf {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap()).join("Cargo.toml");
    let out = Command::new(cargo)
        .args(["metadata", "--format-version", "1", "--offline", "--manifest-path"])
        .arg(&manifest)
        .output()
        .expect("cargo metadata");
    assert!(
        out.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).expect("cargo metadata's JSON");
    let pkg = meta["packages"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "joltc-sys")
        .expect("joltc-sys among the dependencies");
    PathBuf::from(pkg["manifest_path"].as_str().unwrap())
        .parent()
        .unwrap()
        .to_path_buf()
}

fn main() {
    println!("cargo:rerun-if-changed=src/jolt_settings.cpp");
    println!("cargo:rerun-if-changed=build.rs");
    let jolt = joltc_sys_dir().join("JoltC").join("JoltPhysics");
    let mut b = cc::Build::new();
    b.cpp(true)
        .file("src/jolt_settings.cpp")
        .include(&jolt)
        .std("c++17")
        .warnings(false);
    for d in ["JPH_DEBUG_RENDERER", "JPH_PROFILE_ENABLED", "NDEBUG"] {
        b.define(d, None);
    }
    if std::env::var("CARGO_CFG_TARGET_ARCH").as_deref() != Ok("x86_64") {
        b.compile("pile_jolt_settings");
        return;
    }
    for d in [
        "JPH_USE_AVX",
        "JPH_USE_AVX2",
        "JPH_USE_F16C",
        "JPH_USE_FMADD",
        "JPH_USE_LZCNT",
        "JPH_USE_SSE4_1",
        "JPH_USE_SSE4_2",
        "JPH_USE_TZCNT",
    ] {
        b.define(d, None);
    }
    for f in [
        "-mavx2",
        "-mbmi",
        "-mpopcnt",
        "-mlzcnt",
        "-mf16c",
        "-mfma",
        "-mfpmath=sse",
        "-ffp-contract=off",
    ] {
        b.flag_if_supported(f);
    }
    b.compile("pile_jolt_settings");
}

//! Builds the Ceres shim (cpp/ceres_shim.cc) and its `cxx` bridge when the `ceres` feature
//! is on; does nothing otherwise.
//!
//! The shim is one translation unit, always compiled optimised (autodiff on Jets is
//! unusably slow at -O0) and for the build machine's CPU (`-march=native`; set
//! `NAOCALIB_PORTABLE=1` for a binary that runs on any x86-64), against the system's Ceres,
//! glog and Eigen (Debian: libceres-dev, libgoogle-glog-dev, libeigen3-dev).
//! `EIGEN3_INCLUDE_DIR` overrides where Eigen's headers are looked for.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    #[cfg(feature = "ceres")]
    if std::env::var_os("CARGO_FEATURE_CERES").is_some() {
        ceres::build();
    }
}

#[cfg(feature = "ceres")]
mod ceres {
    /// The bridge alone: the Rust around it (`src/solve/ceres/mod.rs`) can change without
    /// the C++ being compiled again.
    const BRIDGE: &str = "src/solve/ceres/bridge.rs";
    const SOURCES: [&str; 2] = ["cpp/ceres_shim.cc", "cpp/ceres_shim.h"];

    pub fn build() {
        println!("cargo:rerun-if-env-changed=EIGEN3_INCLUDE_DIR");
        let eigen = std::env::var("EIGEN3_INCLUDE_DIR")
            .unwrap_or_else(|_| "/usr/include/eigen3".to_string());
        // The Jet arithmetic gains ~20% from the build machine's vector instructions; a
        // binary meant for other machines is built with NAOCALIB_PORTABLE=1.
        println!("cargo:rerun-if-env-changed=NAOCALIB_PORTABLE");
        let native = std::env::var_os("NAOCALIB_PORTABLE").is_none();
        let mut build = cxx_build::bridge(BRIDGE);
        if native {
            // Keep Eigen's alignment that of the generic libceres build, so that no object
            // shared with it changes layout; only the instructions change.
            build
                .flag_if_supported("-march=native")
                .define("EIGEN_MAX_ALIGN_BYTES", "16");
        }
        build
            .file(SOURCES[0])
            .std("c++17")
            // As a system include, so that Eigen's own warnings stay quiet.
            .flag(format!("-isystem{eigen}"))
            .opt_level(2)
            .debug(false)
            .define("NDEBUG", None)
            .flag_if_supported("-Wno-unused-parameter")
            .flag_if_supported("-Wno-deprecated-declarations")
            // False positives inside Eigen's AVX-512 code with GCC 12.
            .flag_if_supported("-Wno-uninitialized")
            .flag_if_supported("-Wno-maybe-uninitialized")
            .compile("naocalib-ceres");
        for lib in ["ceres", "glog"] {
            println!("cargo:rustc-link-lib={lib}");
        }
        println!("cargo:rerun-if-changed={BRIDGE}");
        for file in SOURCES {
            println!("cargo:rerun-if-changed={file}");
        }
    }
}

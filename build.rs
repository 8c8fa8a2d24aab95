//! Builds the Ceres shim (cpp/ceres_shim.cc) and its `cxx` bridge when the `ceres` feature
//! is on; does nothing otherwise.
//!
//! The shim is one translation unit, always compiled optimised (autodiff on Jets is
//! unusably slow at -O0), against the system's Ceres, glog and Eigen (Debian:
//! libceres-dev, libgoogle-glog-dev, libeigen3-dev). `EIGEN3_INCLUDE_DIR` overrides where
//! Eigen's headers are looked for.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    #[cfg(feature = "ceres")]
    if std::env::var_os("CARGO_FEATURE_CERES").is_some() {
        ceres::build();
    }
}

#[cfg(feature = "ceres")]
mod ceres {
    const BRIDGE: &str = "src/solve/ceres.rs";
    const SOURCES: [&str; 2] = ["cpp/ceres_shim.cc", "cpp/ceres_shim.h"];

    pub fn build() {
        println!("cargo:rerun-if-env-changed=EIGEN3_INCLUDE_DIR");
        let eigen = std::env::var("EIGEN3_INCLUDE_DIR")
            .unwrap_or_else(|_| "/usr/include/eigen3".to_string());
        cxx_build::bridge(BRIDGE)
            .file(SOURCES[0])
            .std("c++17")
            // As a system include, so that Eigen's own warnings stay quiet.
            .flag(format!("-isystem{eigen}"))
            .opt_level(2)
            .debug(false)
            .define("NDEBUG", None)
            .flag_if_supported("-Wno-unused-parameter")
            .flag_if_supported("-Wno-deprecated-declarations")
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

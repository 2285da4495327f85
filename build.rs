//! Builds the STEP shim (`cpp/step_shim.cpp`) against Debian's Open CASCADE, only with
//! the `step` feature: the default build needs no C++ compiler and no OCCT.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    #[cfg(feature = "step")]
    step();
}

#[cfg(feature = "step")]
fn step() {
    // Debian's libocct-*-dev put the headers here; OCCT_INCLUDE_DIR / OCCT_LIB_DIR
    // name another installation (7.6 API).
    let include =
        std::env::var("OCCT_INCLUDE_DIR").unwrap_or_else(|_| "/usr/include/opencascade".into());
    println!("cargo:rerun-if-env-changed=OCCT_INCLUDE_DIR");
    println!("cargo:rerun-if-env-changed=OCCT_LIB_DIR");
    if !std::path::Path::new(&include)
        .join("STEPCAFControl_Reader.hxx")
        .exists()
    {
        panic!(
            "feature `step` needs Open CASCADE's headers in {include}: on Debian/Ubuntu \
             `apt-get install libocct-data-exchange-dev libocct-modeling-algorithms-dev`, \
             or set OCCT_INCLUDE_DIR"
        );
    }
    cxx_build::bridge("src/mesh/step_ffi.rs")
        .file("cpp/step_shim.cpp")
        .include(&include)
        .std("c++17")
        // OCCT's headers are noisy under -Wall; the shim's own code is small.
        .flag_if_supported("-Wno-deprecated-declarations")
        .flag_if_supported("-Wno-unused-parameter")
        .compile("fitup_step_shim");
    println!("cargo:rerun-if-changed=cpp/step_shim.cpp");
    println!("cargo:rerun-if-changed=cpp/step_shim.h");
    println!("cargo:rerun-if-changed=cpp/occt_libs.rs");
    if let Ok(dir) = std::env::var("OCCT_LIB_DIR") {
        println!("cargo:rustc-link-search=native={dir}");
    }
    for lib in OCCT_LIBS {
        println!("cargo:rustc-link-lib=dylib={lib}");
    }
}

include!("cpp/occt_libs.rs");

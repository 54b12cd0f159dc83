//! Links the system numerical libraries that linercav calls by FFI:
//! ARPACK-NG (`libarpack2-dev`, found by pkg-config as `arpack`) and METIS
//! (`libmetis-dev`, fill-reducing nested-dissection ordering; no .pc file in Debian).

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    // LAPACK's XERBLA is replaced by linercav's (src/eigen/arpack.rs), which records the error
    // instead of printing on stdout: export it so the shared LAPACK binds to it.
    println!("cargo:rustc-link-arg=-Wl,--export-dynamic-symbol=xerbla_");
    if let Err(e) = pkg_config::Config::new().probe("arpack") {
        panic!(
            "\n\nlinercav needs ARPACK-NG: install the Debian package `libarpack2-dev` \
             (apt-get install -y libarpack2-dev).\npkg-config said: {e}\n\n"
        );
    }
    let metis_found = [
        "/usr/lib/x86_64-linux-gnu",
        "/usr/lib/aarch64-linux-gnu",
        "/usr/lib",
        "/usr/local/lib",
    ]
    .iter()
    .find(|d| std::path::Path::new(&format!("{d}/libmetis.so")).exists());
    match metis_found {
        Some(dir) => {
            println!("cargo:rustc-link-search=native={dir}");
            println!("cargo:rustc-link-lib=dylib=metis");
        }
        None => panic!(
            "\n\nlinercav needs METIS for its fill-reducing ordering: install the Debian package \
             `libmetis-dev` (apt-get install -y libmetis-dev).\n\n"
        ),
    }
}

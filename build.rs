//! Links the system numerical libraries that linercav calls by FFI:
//! ARPACK-NG (`libarpack2-dev`, found by pkg-config as `arpack`) and METIS
//! (`libmetis-dev`, fill-reducing nested-dissection ordering; no .pc file in Debian); and,
//! when Debian's single-threaded OpenBLAS is installed (`libopenblas0-serial`), that library
//! ahead of the BLAS and LAPACK ARPACK was linked against.

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
    link_serial_openblas();
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

/// Links `libopenblas.so.0` from Debian's `openblas-serial` directory, when present, as a
/// direct dependency of the binaries (with a run path to it): the dynamic linker then binds
/// ARPACK's BLAS and LAPACK calls (dgemv, dger, dsteqr ...) to it before the system's
/// `libblas.so.3`, whatever BLAS the machine's alternatives select (the reference BLAS made
/// ARPACK's own work 5 s of the default crankcase's 19 s Lanczos). Single-threaded, so the
/// sums are the same run to run and on any number of cores. Absent: the system's BLAS.
fn link_serial_openblas() {
    let dir = [
        "/usr/lib/x86_64-linux-gnu/openblas-serial",
        "/usr/lib/aarch64-linux-gnu/openblas-serial",
    ]
    .into_iter()
    .find(|d| std::path::Path::new(&format!("{d}/libopenblas.so.0")).exists());
    if let Some(dir) = dir {
        println!("cargo:rustc-link-arg=-Wl,--no-as-needed");
        println!("cargo:rustc-link-arg={dir}/libopenblas.so.0");
        println!("cargo:rustc-link-arg=-Wl,--as-needed");
        println!("cargo:rustc-link-arg=-Wl,-rpath,{dir}");
    }
}

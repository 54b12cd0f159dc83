//! Fuzz target of the Gmsh MSH 4.1 reader and the mesh checks: any bytes must give a mesh or
//! an error, never a panic, an abort or a runaway allocation.
//! Run from the repository root: `cargo install cargo-fuzz`, seed the corpus with
//! `mkdir -p fuzz/corpus/msh && cp tests/fixtures/*.msh fuzz/corpus/msh/`, then
//! `cargo +nightly fuzz run msh -- -max_total_time=600`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(mut mesh) = linercav::mesh::gmsh::parse(std::path::Path::new("fuzz.msh"), text) {
            let _ = linercav::fem::element::check_mesh(&mut mesh);
        }
    }
});

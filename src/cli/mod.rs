//! The command-line front end's own pieces: what shows progress on a terminal, and the signal
//! handler. The commands themselves are library functions in [`linercav::api`].

pub mod progress;

/// Installs the front end: progress on a terminal ([`progress::indicator`]), the removal of
/// temporary files when SIGINT, SIGTERM or SIGHUP stops the process
/// ([`linercav::files::stop_cleanly`]), and SIGXFSZ ignored: a write beyond the file-size
/// limit (`ulimit -f`, a scheduler's) then fails as an error, which removes the temporary
/// file and names the output, where the signal killed the process and left the temporary.
pub fn install() {
    linercav::api::progress::set_front_end(progress::indicator);
    let _ = ctrlc::set_handler(linercav::files::stop_cleanly);
    // SAFETY: sets the disposition of one signal to "ignore"; no handler code runs.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
}

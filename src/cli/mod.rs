//! The command-line front end's own pieces: what shows progress on a terminal, and the signal
//! handler. The commands themselves are library functions in [`linercav::api`].

pub mod progress;

/// Installs the front end: progress on a terminal ([`progress::indicator`]) and the removal of
/// temporary files when SIGINT, SIGTERM or SIGHUP stops the process
/// ([`linercav::files::stop_cleanly`]).
pub fn install() {
    linercav::api::progress::set_front_end(progress::indicator);
    let _ = ctrlc::set_handler(linercav::files::stop_cleanly);
}

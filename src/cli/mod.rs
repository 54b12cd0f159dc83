//! The command-line front end's own pieces: what shows progress on a terminal, and the signal
//! handler. The commands themselves are library functions in [`linercav::api`].

pub mod progress;

/// Installs the front end: progress on a terminal ([`progress::indicator`]), the removal of
/// temporary files when SIGINT, SIGTERM or SIGHUP stops the process
/// ([`linercav::files::stop_cleanly`]) or an abort ends it ([`on_abort`]), and SIGXFSZ ignored: a write beyond the file-size
/// limit (`ulimit -f`, a scheduler's) then fails as an error, which removes the temporary
/// file and names the output, where the signal killed the process and left the temporary.
pub fn install() {
    linercav::api::progress::set_front_end(progress::indicator);
    let _ = ctrlc::set_handler(linercav::files::stop_cleanly);
    // SAFETY: sets the disposition of one signal to "ignore"; no handler code runs.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
    out_of_memory_is_an_error();
    // SAFETY: `on_abort` only writes a fixed message, removes files through locks it does not
    // wait for, and re-raises the signal with its default action.
    unsafe {
        libc::signal(
            libc::SIGABRT,
            on_abort as extern "C" fn(libc::c_int) as *const () as libc::sighandler_t,
        );
    }
}

/// SIGABRT (an allocation that failed beyond the estimate: exit 134): says so, removes the
/// temporaries ([`linercav::files::remove_temporaries_at_abort`]; a staged output directory
/// was left behind) and goes on with the abort.
extern "C" fn on_abort(_: libc::c_int) {
    const MSG: &[u8] = b"linercav: aborted (out of memory beyond the estimate, or an internal error); temporary files removed, outputs left as they were\n";
    // SAFETY: write(2) of a static buffer; signal(2) and raise(3) restore and deliver the
    // default action (the process ends with SIGABRT, as without this handler)
    unsafe {
        libc::write(2, MSG.as_ptr().cast(), MSG.len());
        linercav::files::remove_temporaries_at_abort();
        libc::signal(libc::SIGABRT, libc::SIG_DFL);
        libc::raise(libc::SIGABRT);
    }
}

/// A panic that is an allocation failure (faer's and the standard library's fallible
/// allocations unwrap theirs: "AllocError", "capacity overflow") ends the run as a failure,
/// exit 1, with what failed and where, its temporaries removed; a run the estimates let
/// through should not get there, but a machine's memory can change under a run. Every other
/// panic keeps the default report (a bug: exit 101).
fn out_of_memory_is_an_error() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let msg = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.contains("AllocError") || msg.contains("capacity overflow") {
            linercav::files::remove_temporaries_at_abort();
            let at = info
                .location()
                .map(|l| format!(" at {}:{}", l.file(), l.line()))
                .unwrap_or_default();
            eprintln!("error: out of memory: an allocation failed{at} ({msg}): the run needed more than its estimate or the machine had less than it reported; temporary files removed, outputs left as they were");
            std::process::exit(1);
        }
        default(info);
    }));
}

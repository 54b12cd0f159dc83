//! The command-line front end's own pieces: what shows progress on a terminal, and the signal
//! handler. The commands themselves are library functions in [`linercav::api`].

pub mod progress;

/// Installs the front end: progress on a terminal ([`progress::indicator`]), the removal of
/// temporary files when SIGINT, SIGTERM or SIGHUP stops the process
/// ([`linercav::files::stop_cleanly`]) or an allocation fails ([`out_of_memory_is_an_error`]),
/// and SIGXFSZ ignored: a write beyond the file-size
/// limit (`ulimit -f`, a scheduler's) then fails as an error, which removes the temporary
/// file and names the output, where the signal killed the process and left the temporary.
pub fn install() {
    linercav::api::progress::set_front_end(progress::indicator);
    stop_on_signals();
    // SAFETY: sets the disposition of one signal to "ignore"; no handler code runs.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
    out_of_memory_is_an_error();
}

/// SIGINT, SIGTERM and SIGHUP stop the process cleanly ([`linercav::files::stop_cleanly`],
/// exit 128 + the signal's number as a shell reports it: 130, 143, 129), from a thread that
/// waits for them (no work in the signal handler itself). A second signal during the cleanup
/// waits for it.
fn stop_on_signals() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            linercav::files::stop_cleanly(128 + signal);
        }
    });
}

/// A panic that is an allocation failure (faer unwraps its fallible allocations' `AllocError`)
/// ends the run as a failure, exit 1, with what failed and where, its temporaries removed
/// ([`linercav::files::remove_temporaries_for_exit`]); a run the estimates let through should
/// not get there, but a machine's memory can change under a run. Every other panic keeps the
/// default report (a bug, "capacity overflow" from an unchecked size among them: exit 101).
/// An allocation the standard library cannot make aborts (exit 134); its staging directory
/// is removed by the next run into the same place ([`linercav::files::OutputDir::create`]).
fn out_of_memory_is_an_error() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let msg = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.contains("AllocError") {
            let removed = linercav::files::remove_temporaries_for_exit();
            let at = info
                .location()
                .map(|l| format!(" at {}:{}", l.file(), l.line()))
                .unwrap_or_default();
            let left = if removed {
                "temporary files removed, outputs left as they were"
            } else {
                "temporary files may be left (a move of outputs was under way)"
            };
            // best effort (a standard error that cannot be written keeps the exit code)
            use std::io::Write as _;
            let _ = writeln!(std::io::stderr(), "error: out of memory: an allocation failed{at} ({msg}): the run needed more than its estimate or the machine had less than it reported; {left}");
            std::process::exit(1);
        }
        default(info);
    }));
}

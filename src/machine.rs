//! What the machine can hold: memory available to a new job (Linux `/proc/meminfo`, and the
//! address-space limit a batch scheduler or `prlimit --as` sets).

/// Memory available for new work [bytes]: the smaller of the system's (`MemAvailable`: what can
/// be allocated without swapping, else `MemTotal`, else 8 GiB when the kernel does not say)
/// and the process's address-space limit (RLIMIT_AS; under a 2 GB cap the default ROM build
/// aborted in an allocation instead of being refused up front).
pub fn available_memory() -> u64 {
    system_memory().min(address_space_limit())
}

/// RLIMIT_AS of the process [bytes] (u64::MAX when unlimited or unknown).
fn address_space_limit() -> u64 {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes one rlimit into the struct it is given
    if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut r) } != 0 || r.rlim_cur == libc::RLIM_INFINITY
    {
        return u64::MAX;
    }
    r.rlim_cur
}

fn system_memory() -> u64 {
    let Ok(text) = std::fs::read_to_string("/proc/meminfo") else {
        return 8 << 30;
    };
    let field = |name: &str| {
        text.lines()
            .find(|l| l.starts_with(name))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|kb| kb.parse::<u64>().ok())
            .map(|kb| kb * 1024)
    };
    field("MemAvailable:")
        .or_else(|| field("MemTotal:"))
        .unwrap_or(8 << 30)
}

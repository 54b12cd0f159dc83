//! What the machine can hold: memory available to a new job (Linux `/proc/meminfo`).

/// Memory available for new work [bytes]: `MemAvailable` (what can be allocated without
/// swapping), else `MemTotal`, else 8 GiB when the kernel does not say.
pub fn available_memory() -> u64 {
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

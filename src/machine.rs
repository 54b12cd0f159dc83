//! What the machine can hold: memory available to a new job (Linux `/proc/meminfo`, the
//! address-space limit a batch scheduler or `prlimit --as` sets, and the memory cgroup's
//! limit a container or a scheduler sets), and a way to hand freed memory back to it.

/// Memory available for new work \[bytes\]: the smaller of the system's (`MemAvailable`: what can
/// be allocated without swapping, else `MemTotal`, else 8 GiB when the kernel does not say)
/// and the process's address-space limit (RLIMIT_AS; under a 2 GB cap the default ROM build
/// aborted in an allocation instead of being refused up front).
pub fn available_memory() -> u64 {
    available_memory_from().0
}

/// [`available_memory`] and which bound it is: "the machine", "the address-space limit
/// (ulimit -v, prlimit --as)" or "the memory cgroup".
pub fn available_memory_from() -> (u64, &'static str) {
    [
        (system_memory(), "the machine"),
        (
            address_space_left(address_space_limit()),
            ADDRESS_SPACE_BOUND,
        ),
        (
            cgroup_available(&|p| std::fs::read_to_string(p).ok()),
            "the memory cgroup",
        ),
    ]
    .into_iter()
    .min_by_key(|&(b, _)| b)
    .expect("three bounds")
}

/// The label of the address-space bound in [`available_memory_from`].
pub const ADDRESS_SPACE_BOUND: &str = "the address-space limit (ulimit -v, prlimit --as)";

/// The resident memory a cap `limit` on the address space leaves room for \[bytes\]:
///   (limit - [`ADDRESS_SPACE_HEADROOM`]) / ([`VIRTUAL_PER_RESIDENT_PERCENT`] / 100),
/// the headroom for what every run maps whatever its size (the binary and its libraries,
/// thread stacks, the allocators' first arenas), the ratio for the address space a run maps
/// per byte of its resident estimate beyond that. Under a 700 MB cap an estimate of 0.32 GB
/// against the bare limit aborted in an allocation. Before the command line fitted its
/// allocator to a cap (`fit_allocator_to_address_space` in `main.rs`), mimalloc's arenas
/// made the default engine's `modes --assembly --full` map 13.2 GB for 4.6 GB resident.
pub fn address_space_left(limit: u64) -> u64 {
    if limit == u64::MAX {
        return u64::MAX;
    }
    limit.saturating_sub(ADDRESS_SPACE_HEADROOM) / VIRTUAL_PER_RESIDENT_PERCENT * 100
}

/// Address space every run maps under a cap beyond its estimate \[bytes\] (the binary and
/// its libraries, thread stacks, the allocators' first arenas): `modes` of the 3,936-DOF
/// Abaqus liner deck (estimate 0.09 GB, 0.09 GB resident) peaked at 0.74 GB.
pub const ADDRESS_SPACE_HEADROOM: u64 = 768 << 20;

/// Address space mapped per byte of the resident estimate, beyond the headroom, in percent:
/// 125, above the largest ratio measured under an 8 GB cap, (VmPeak - headroom) / estimate:
/// the default liner's `modes` (VmPeak 1.55 GB, estimate 0.74 GB) 1.00, the default engine's
/// `modes --assembly --full` (6.27 GB, estimate 5.29 GB) 1.03, the 754k-DOF casting's
/// `modes` (5.86 GB, estimate 5.49 GB) 0.92. Both large runs fit under 8 GB. The casting was refused there
/// before: the old rule counted twice the estimate plus 0.5 GB of address space and let a
/// run take 80 % of what was left. The estimates
/// themselves lie above the resident peaks (`crate::scene::budget::modal_solve`), and under a
/// cap the limit is the whole of what is left (the 80 % margin is the machine's, which other
/// processes share, [`crate::scene::budget::Limits`]).
pub const VIRTUAL_PER_RESIDENT_PERCENT: u64 = 125;

/// What the process's memory cgroup still allows \[bytes\]: limit - usage of its cgroup (v2
/// `memory.max` - `memory.current`; v1 `memory.limit_in_bytes` - `memory.usage_in_bytes`), as a
/// container runtime or a batch scheduler sets it; u64::MAX when unlimited or not found.
/// `read` reads a file (a parameter so that the parsing can be tested).
pub fn cgroup_available(read: &dyn Fn(&str) -> Option<String>) -> u64 {
    let Some(groups) = read("/proc/self/cgroup") else {
        return u64::MAX;
    };
    let num = |p: &str| read(p).and_then(|t| t.trim().parse::<u64>().ok());
    let mut best = u64::MAX;
    for line in groups.lines() {
        let mut f = line.splitn(3, ':');
        let (_, controllers, path) = (f.next(), f.next().unwrap_or(""), f.next().unwrap_or(""));
        let path = path.trim_end_matches('/');
        let (root, max, current) = if controllers.is_empty() {
            ("/sys/fs/cgroup", "memory.max", "memory.current")
        } else if controllers.split(',').any(|c| c == "memory") {
            (
                "/sys/fs/cgroup/memory",
                "memory.limit_in_bytes",
                "memory.usage_in_bytes",
            )
        } else {
            continue;
        };
        // the group's own directory, else the namespace's root (a container sees its group there)
        for dir in [format!("{root}{path}"), root.to_string()] {
            if let Some(limit) = num(&format!("{dir}/{max}")) {
                // v1 says "no limit" with a number near 2^63
                if limit < 1 << 60 {
                    let used = num(&format!("{dir}/{current}")).unwrap_or(0);
                    best = best.min(limit.saturating_sub(used));
                }
                break;
            }
        }
    }
    best
}

/// Whether the process runs under an address-space limit (`ulimit -v`, `prlimit --as`).
pub fn address_space_capped() -> bool {
    address_space_limit() != u64::MAX
}

/// RLIMIT_AS of the process \[bytes\] (u64::MAX when unlimited or unknown).
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

/// The allocator's way to hand the memory it keeps after a free back to the operating system,
/// set once by the program that chose the allocator ([`set_memory_release`]).
static RELEASE: std::sync::OnceLock<fn()> = std::sync::OnceLock::new();

/// Sets what [`release_memory`] calls (the command line sets mimalloc's collection; the
/// system allocator needs none: it unmaps large blocks when they are freed).
pub fn set_memory_release(release: fn()) {
    let _ = RELEASE.set(release);
}

/// Hands freed memory back to the operating system now, where the allocator would keep it
/// for reuse: called after large arrays are let go so that the next large allocation (a
/// factor) does not come on top of them in resident memory.
pub fn release_memory() {
    if let Some(release) = RELEASE.get() {
        release();
    }
}

#[cfg(test)]
mod tests {
    use super::{
        address_space_left, cgroup_available, ADDRESS_SPACE_HEADROOM, VIRTUAL_PER_RESIDENT_PERCENT,
    };

    /// Regression (issue 40): under a 700 MB address-space cap an estimate of 0.32 GB was
    /// let through against the bare cap and the run aborted in an allocation; the cap now
    /// leaves the headroom out and counts the address space mapped per resident byte, and no
    /// cap leaves everything.
    #[test]
    fn regression_an_address_space_cap_keeps_its_headroom() {
        assert_eq!(address_space_left(u64::MAX), u64::MAX);
        assert_eq!(
            address_space_left(700_000_000),
            0,
            "700 MB is below the headroom"
        );
        assert_eq!(
            address_space_left(8_000_000_000),
            (8_000_000_000 - ADDRESS_SPACE_HEADROOM) / VIRTUAL_PER_RESIDENT_PERCENT * 100
        );
        assert_eq!(address_space_left(ADDRESS_SPACE_HEADROOM / 2), 0);
    }
    use std::collections::HashMap;

    fn reader(files: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
        let m: HashMap<String, String> = files
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        move |p: &str| m.get(p).cloned()
    }

    /// Verification: a v2 group with a limit gives limit - usage; "max" is unlimited; a v1
    /// memory group's limit is read from its directory, or from the namespace's root, and the
    /// v1 "unlimited" number is ignored.
    #[test]
    fn verification_cgroup_limits_are_read() {
        let v2 = reader(&[
            ("/proc/self/cgroup", "0::/job/42\n"),
            ("/sys/fs/cgroup/job/42/memory.max", "8589934592\n"),
            ("/sys/fs/cgroup/job/42/memory.current", "1073741824\n"),
        ]);
        assert_eq!(cgroup_available(&v2), 7 << 30);
        let v2_max = reader(&[
            ("/proc/self/cgroup", "0::/\n"),
            ("/sys/fs/cgroup/memory.max", "max\n"),
        ]);
        assert_eq!(cgroup_available(&v2_max), u64::MAX);
        let v1 = reader(&[
            (
                "/proc/self/cgroup",
                "5:devices:/\n4:memory:/slurm/uid_0/job_7\n0::/\n",
            ),
            ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "4294967296"),
            ("/sys/fs/cgroup/memory/memory.usage_in_bytes", "294967296"),
        ]);
        assert_eq!(cgroup_available(&v1), 4_000_000_000);
        let v1_unlimited = reader(&[
            ("/proc/self/cgroup", "4:memory:/x\n"),
            (
                "/sys/fs/cgroup/memory/x/memory.limit_in_bytes",
                "9223372036854771712",
            ),
        ]);
        assert_eq!(cgroup_available(&v1_unlimited), u64::MAX);
        assert_eq!(cgroup_available(&reader(&[])), u64::MAX);
    }
}

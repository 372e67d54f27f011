//! The memory this process may still allocate, for cost gates that refuse a
//! request before allocating it (the engine's budget, and reducers such as
//! the NAR identifier that size a regression from their parameters).
//!
//! Three limits apply on Linux, and the smallest one decides:
//! - the machine's available memory (`MemAvailable` of `/proc/meminfo`);
//! - the address-space limit `RLIMIT_AS` (`ulimit -v`), which counts the
//!   virtual size: what is left is the limit minus `VmSize` of
//!   `/proc/self/status`;
//! - the memory limit of the process's cgroup and of each of its ancestors
//!   (`memory.max` minus `memory.current` for cgroup v2,
//!   `memory.limit_in_bytes` minus `memory.usage_in_bytes` for v1), the
//!   cgroup named by `/proc/self/cgroup`.
//!
//! Each counts what the allocator holds free for this process's own later
//! requests as used (a front end that keeps freed memory, as the engine
//! does: `ssm_kernel::heap::retain_freed_memory`): that part is added back
//! to each room (glibc's `mallinfo2().fordblks`).
//!
//! This is not part of the plugin ABI: each side compiles its own copy.

use std::path::PathBuf;

/// The memory left to this process, and which limit set it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemoryRoom {
    /// Bytes that may still be allocated.
    pub bytes: f64,
    /// The limit that decides, for messages (e.g. "address-space limit (ulimit -v)").
    pub source: &'static str,
}

/// Bytes assumed when no limit can be read (not Linux, no `/proc`).
const ASSUMED: f64 = 8.0 * 1024.0 * 1024.0 * 1024.0;

/// Reads the three limits of this process now (see the module's text);
/// 8 GiB, "assumed", when none can be read.
pub fn memory_room() -> MemoryRoom {
    let read = |p: &str| std::fs::read_to_string(p).ok();
    let cgroups = read("/proc/self/cgroup")
        .map(|text| {
            cgroup_files(&text)
                .into_iter()
                .filter_map(|(limit, usage)| {
                    let limit = std::fs::read_to_string(limit).ok()?;
                    Some((limit, std::fs::read_to_string(usage).ok()))
                })
                .collect::<Vec<_>>()
        })
        .unwrap_or_default();
    smallest(
        read("/proc/meminfo").as_deref(),
        address_space_limit(),
        read("/proc/self/status").as_deref(),
        &cgroups,
        reusable_heap(),
    )
}

/// Bytes the allocator holds free for this process's own later requests
/// (glibc's `mallinfo2().fordblks`); 0 where it cannot be read.
fn reusable_heap() -> f64 {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: mallinfo2 only reads the allocator's statistics.
        unsafe { libc::mallinfo2() }.fordblks as f64
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        0.0
    }
}

/// The address space left under `RLIMIT_AS` (`ulimit -v`): the limit minus
/// `VmSize` of `/proc/self/status`; `None` without such a limit. Unlike the
/// other two limits it counts reserved pages that were never touched, such
/// as the per-thread buffers of dense matrix kernels.
pub fn address_space_room() -> Option<f64> {
    let limit = address_space_limit()?;
    let status = std::fs::read_to_string("/proc/self/status").ok();
    let mapped = status
        .as_deref()
        .and_then(|t| kib_field(t, "VmSize:"))
        .unwrap_or(0.0);
    Some((limit - mapped).max(0.0) + reusable_heap())
}

/// `RLIMIT_AS` in bytes; `None` when unlimited or unreadable.
fn address_space_limit() -> Option<f64> {
    let mut lim = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes the struct it is given and nothing else.
    let rc = unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut lim) };
    (rc == 0 && lim.rlim_cur != libc::RLIM_INFINITY).then_some(lim.rlim_cur as f64)
}

/// The smallest room from the texts of `/proc/meminfo`, `/proc/self/status`,
/// the address-space limit and the `(limit, usage)` texts of the cgroups,
/// each with the allocator's `reusable` bytes added back.
fn smallest(
    meminfo: Option<&str>,
    rlimit_as: Option<f64>,
    status: Option<&str>,
    cgroups: &[(String, Option<String>)],
    reusable: f64,
) -> MemoryRoom {
    let mut rooms = Vec::new();
    if let Some(b) = meminfo.and_then(|t| kib_field(t, "MemAvailable:")) {
        rooms.push((b, "available memory (MemAvailable)"));
    }
    if let Some(limit) = rlimit_as {
        let mapped = status.and_then(|t| kib_field(t, "VmSize:")).unwrap_or(0.0);
        rooms.push(((limit - mapped).max(0.0), "address-space limit (ulimit -v)"));
    }
    for (limit, usage) in cgroups {
        if let Some(limit) = cgroup_number(limit) {
            let used = usage.as_deref().and_then(cgroup_number).unwrap_or(0.0);
            rooms.push(((limit - used).max(0.0), "cgroup memory limit"));
        }
    }
    rooms.into_iter().min_by(|a, b| a.0.total_cmp(&b.0)).map_or(
        MemoryRoom {
            bytes: ASSUMED,
            source: "assumed",
        },
        |(bytes, source)| MemoryRoom {
            bytes: bytes + reusable,
            source,
        },
    )
}

/// The value in bytes of a `Name:   123 kB` line of `/proc` text.
fn kib_field(text: &str, name: &str) -> Option<f64> {
    text.lines()
        .find_map(|l| l.strip_prefix(name))
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|kb| kb.parse::<f64>().ok())
        .map(|kb| kb * 1024.0)
}

/// A cgroup limit or usage file's number; `None` for `max` (no limit) or
/// text that is not a number.
fn cgroup_number(text: &str) -> Option<f64> {
    text.trim().parse::<u64>().ok().map(|b| b as f64)
}

/// The `(limit, usage)` files of the process's memory cgroup and of each of
/// its ancestors up to the mount's root, from the text of
/// `/proc/self/cgroup`: the v1 `memory` controller's line (`N:memory:/path`,
/// possibly with other controllers) under `/sys/fs/cgroup/memory`, and the v2
/// line (`0::/path`) under `/sys/fs/cgroup`.
fn cgroup_files(proc_cgroup: &str) -> Vec<(PathBuf, PathBuf)> {
    let mut files = Vec::new();
    for line in proc_cgroup.lines() {
        let mut parts = line.splitn(3, ':');
        let (Some(_), Some(controllers), Some(path)) = (parts.next(), parts.next(), parts.next())
        else {
            continue;
        };
        let (root, limit, usage) = if controllers.is_empty() {
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
        let mut dir = PathBuf::from(root);
        let mut levels = vec![dir.clone()];
        for part in path.split('/').filter(|p| !p.is_empty() && *p != "..") {
            dir.push(part);
            levels.push(dir.clone());
        }
        files.extend(
            levels
                .into_iter()
                .rev()
                .map(|d| (d.join(limit), d.join(usage))),
        );
    }
    files
}

#[cfg(test)]
mod tests {
    use super::*;

    const GIB: f64 = 1024.0 * 1024.0 * 1024.0;

    #[test]
    fn proc_fields_are_read_in_kib() {
        let meminfo =
            "MemTotal:       24000000 kB\nMemFree:  100 kB\nMemAvailable:   16000000 kB\n";
        assert_eq!(
            kib_field(meminfo, "MemAvailable:"),
            Some(16_000_000.0 * 1024.0)
        );
        let status = "Name:\tssm-engine\nVmPeak:\t  9000 kB\nVmSize:\t    3892 kB\n";
        assert_eq!(kib_field(status, "VmSize:"), Some(3892.0 * 1024.0));
        assert_eq!(kib_field(status, "VmRSS:"), None);
    }

    #[test]
    fn cgroup_numbers_and_max() {
        assert_eq!(cgroup_number("4294967296\n"), Some(4.0 * GIB));
        assert_eq!(cgroup_number("max\n"), None);
        assert_eq!(cgroup_number(""), None);
    }

    #[test]
    fn cgroup_files_walk_from_the_leaf_to_the_root() {
        let v2 = cgroup_files("0::/user.slice/job\n");
        let v2: Vec<_> = v2.iter().map(|(l, _)| l.to_str().unwrap()).collect();
        assert_eq!(
            v2,
            [
                "/sys/fs/cgroup/user.slice/job/memory.max",
                "/sys/fs/cgroup/user.slice/memory.max",
                "/sys/fs/cgroup/memory.max",
            ]
        );
        let v1 = cgroup_files("9:name=systemd:/\n4:memory:/api/37bc\n3:cpu,cpuacct:/\n0::/\n");
        let v1: Vec<_> = v1
            .iter()
            .map(|(l, u)| (l.to_str().unwrap(), u.to_str().unwrap()))
            .collect();
        assert_eq!(
            v1[0].0,
            "/sys/fs/cgroup/memory/api/37bc/memory.limit_in_bytes"
        );
        assert_eq!(
            v1[0].1,
            "/sys/fs/cgroup/memory/api/37bc/memory.usage_in_bytes"
        );
        assert_eq!(v1[2].0, "/sys/fs/cgroup/memory/memory.limit_in_bytes");
        // then the v2 root of the hybrid layout
        assert_eq!(v1[3].0, "/sys/fs/cgroup/memory.max");
        assert_eq!(v1.len(), 4);
    }

    #[test]
    fn the_smallest_limit_decides() {
        let meminfo = Some("MemAvailable:   16777216 kB\n"); // 16 GiB
        let status = Some("VmSize:\t 1048576 kB\n"); // 1 GiB mapped
        let none = smallest(meminfo, None, status, &[], 0.0);
        assert_eq!(none.bytes, 16.0 * GIB);
        assert_eq!(none.source, "available memory (MemAvailable)");
        // ulimit -v 8 GiB with 1 GiB mapped leaves 7 GiB
        let ulimit = smallest(meminfo, Some(8.0 * GIB), status, &[], 0.0);
        assert_eq!(ulimit.bytes, 7.0 * GIB);
        assert_eq!(ulimit.source, "address-space limit (ulimit -v)");
        // half a GiB the allocator holds free for the process is room again
        let kept = smallest(meminfo, Some(8.0 * GIB), status, &[], 0.5 * GIB);
        assert_eq!(kept.bytes, 7.5 * GIB);
        assert_eq!(kept.source, "address-space limit (ulimit -v)");
        // a 4 GiB cgroup with 1 GiB used leaves 3 GiB; "max" levels count for nothing
        let cg = [
            ("max\n".to_owned(), Some("123\n".to_owned())),
            ("4294967296\n".to_owned(), Some("1073741824\n".to_owned())),
            ("9223372036854771712\n".to_owned(), None),
        ];
        let cgroup = smallest(meminfo, Some(8.0 * GIB), status, &cg, 0.0);
        assert_eq!(cgroup.bytes, 3.0 * GIB);
        assert_eq!(cgroup.source, "cgroup memory limit");
        // nothing readable
        assert_eq!(smallest(None, None, None, &[], 0.0).bytes, ASSUMED);
    }
}

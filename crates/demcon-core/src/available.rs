//! How much memory this process may still allocate: the least of what the machine has free
//! (`MemAvailable` of `/proc/meminfo`), what its own address-space limit leaves
//! (`RLIMIT_AS`, `ulimit -v`, less the address space it already maps: `VmSize`), and what its
//! cgroup's memory limit leaves (cgroup v2 `memory.max`, v1 `memory.limit_in_bytes`, less the
//! usage, at its own level and every level above). A check against `MemAvailable` alone
//! passed `demcon tile --repeat 50,50,50` under `ulimit -v 4000000`, which then aborted on an
//! allocation of 3 GB.
//!
//! Everything is read from `/proc` and `/sys/fs/cgroup` (Linux); the parsing is in pure
//! functions, tested on the files' text.

use std::path::{Path, PathBuf};

/// What bounds the memory a process may still allocate.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MemoryBound {
    /// The machine's free memory, `MemAvailable` of `/proc/meminfo`.
    MemAvailable,
    /// The process's address-space limit (`RLIMIT_AS`, `ulimit -v`) less what it maps.
    AddressSpace {
        /// The soft limit (bytes).
        limit: u64,
        /// The address space the process maps now, `VmSize` (bytes).
        mapped: u64,
    },
    /// A memory cgroup's limit less its usage (page cache it may reclaim left out).
    Cgroup {
        /// The cgroup's folder.
        dir: PathBuf,
        /// Its limit (bytes).
        limit: u64,
        /// Its usage less the inactive page cache (bytes).
        used: u64,
    },
}

impl std::fmt::Display for MemoryBound {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::MemAvailable => write!(f, "available memory (MemAvailable in /proc/meminfo)"),
            Self::AddressSpace { limit, mapped } => write!(
                f,
                "address space left to this process (its limit RLIMIT_AS, `ulimit -v`, of {:.3e} bytes \
                 less the {:.3e} bytes it maps)",
                *limit as f64, *mapped as f64
            ),
            Self::Cgroup { dir, limit, used } => write!(
                f,
                "memory left in the cgroup {} (its limit of {:.3e} bytes less {:.3e} bytes in use)",
                dir.display(),
                *limit as f64,
                *used as f64
            ),
        }
    }
}

/// The memory a process may still allocate and what bounds it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AvailableMemory {
    /// Bytes.
    pub bytes: u64,
    /// The bound that gives [`Self::bytes`].
    pub bound: MemoryBound,
}

/// Memory this process may still allocate (bytes): the least of `MemAvailable`, the
/// address-space limit less `VmSize`, and every memory cgroup limit above the process less its
/// usage; `None` where none of them can be read (not Linux).
pub fn available_memory() -> Option<u64> {
    available_memory_bound().map(|a| a.bytes)
}

/// [`available_memory`] with the bound that gives it, for messages.
pub fn available_memory_bound() -> Option<AvailableMemory> {
    let read = |p: &str| std::fs::read_to_string(p).ok();
    let mut all = Vec::new();
    if let Some(b) = read("/proc/meminfo").and_then(|t| kib_field(&t, "MemAvailable:")) {
        all.push(AvailableMemory {
            bytes: b,
            bound: MemoryBound::MemAvailable,
        });
    }
    if let (Some(limit), Some(mapped)) = (
        read("/proc/self/limits").and_then(|t| address_space_limit(&t)),
        read("/proc/self/status").and_then(|t| kib_field(&t, "VmSize:")),
    ) {
        all.push(AvailableMemory {
            bytes: limit.saturating_sub(mapped),
            bound: MemoryBound::AddressSpace { limit, mapped },
        });
    }
    if let (Some(cgroup), Some(mountinfo)) = (read("/proc/self/cgroup"), read("/proc/self/mountinfo")) {
        for (dir, top, version) in cgroup_dirs(&cgroup, &mountinfo) {
            all.extend(cgroup_levels(&dir, &top, version));
        }
    }
    least(all)
}

/// The least of `candidates` (the first on a tie).
fn least(candidates: Vec<AvailableMemory>) -> Option<AvailableMemory> {
    candidates
        .into_iter()
        .fold(None, |best: Option<AvailableMemory>, c| match best {
            Some(b) if b.bytes <= c.bytes => Some(b),
            _ => Some(c),
        })
}

/// A `Name:   123 kB` line of `/proc/meminfo` or `/proc/self/status`, in bytes.
fn kib_field(text: &str, name: &str) -> Option<u64> {
    text.lines()
        .find_map(|l| l.strip_prefix(name))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .map(|kb| kb.saturating_mul(1024))
}

/// The soft address-space limit of `/proc/self/limits` (`Max address space  SOFT  HARD
/// bytes`), bytes; `None` when unlimited.
fn address_space_limit(limits: &str) -> Option<u64> {
    let rest = limits.lines().find_map(|l| l.strip_prefix("Max address space"))?;
    rest.split_whitespace().next()?.parse().ok()
}

/// A cgroup memory limit file (v2 `memory.max`: a number or `max`; v1
/// `memory.limit_in_bytes`: a number, about 2⁶³ when unlimited), bytes; `None` when unlimited.
fn cgroup_limit(text: &str) -> Option<u64> {
    let v: u64 = text.trim().parse().ok()?;
    (v < 1 << 62).then_some(v)
}

/// A `key value` line of a cgroup's `memory.stat`.
fn stat_field(text: &str, key: &str) -> Option<u64> {
    text.lines().find_map(|l| {
        let (k, v) = l.split_once(' ')?;
        (k == key).then(|| v.trim().parse().ok()).flatten()
    })
}

/// The cgroup hierarchy's kind: the file names differ.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum CgroupVersion {
    /// cgroup v2 (`memory.max`, `memory.current`, `inactive_file`).
    V2,
    /// cgroup v1's memory controller (`memory.limit_in_bytes`, `memory.usage_in_bytes`,
    /// `total_inactive_file`).
    V1,
}

/// The process's memory cgroup folders, each with the folder of its hierarchy's mount (the
/// top of the walk up) and the hierarchy's version, from `/proc/self/cgroup` and
/// `/proc/self/mountinfo`.
fn cgroup_dirs(cgroup: &str, mountinfo: &str) -> Vec<(PathBuf, PathBuf, CgroupVersion)> {
    // mountinfo: `id parent major:minor root mount-point options… - fstype source super-options`.
    let mounts: Vec<(&str, &str, &str, &str)> = mountinfo
        .lines()
        .filter_map(|l| {
            let (head, tail) = l.split_once(" - ")?;
            let head: Vec<&str> = head.split_whitespace().collect();
            let tail: Vec<&str> = tail.split_whitespace().collect();
            Some((
                *head.get(3)?,
                *head.get(4)?,
                *tail.first()?,
                *tail.get(2).unwrap_or(&""),
            ))
        })
        .collect();
    let mut out = Vec::new();
    for line in cgroup.lines() {
        // `hierarchy-id:controllers:path`; v2 is `0::path`.
        let mut parts = line.splitn(3, ':');
        let (Some(id), Some(controllers), Some(path)) = (parts.next(), parts.next(), parts.next()) else {
            continue;
        };
        let version = if id == "0" && controllers.is_empty() {
            CgroupVersion::V2
        } else if controllers.split(',').any(|c| c == "memory") {
            CgroupVersion::V1
        } else {
            continue;
        };
        let mount = mounts.iter().find(|(_, _, fstype, opts)| match version {
            CgroupVersion::V2 => *fstype == "cgroup2",
            CgroupVersion::V1 => *fstype == "cgroup" && opts.split(',').any(|o| o == "memory"),
        });
        let Some((root, point, _, _)) = mount else {
            continue;
        };
        // The path is relative to the hierarchy's root; the mount shows `root` at `point`.
        let below = path.strip_prefix(root).unwrap_or(path).trim_start_matches('/');
        let top = PathBuf::from(point);
        out.push((top.join(below), top, version));
    }
    out
}

/// What each level of a cgroup from `dir` up to `top` leaves (those with a limit).
fn cgroup_levels(dir: &Path, top: &Path, version: CgroupVersion) -> Vec<AvailableMemory> {
    let (limit_file, usage_file, inactive_key) = match version {
        CgroupVersion::V2 => ("memory.max", "memory.current", "inactive_file"),
        CgroupVersion::V1 => (
            "memory.limit_in_bytes",
            "memory.usage_in_bytes",
            "total_inactive_file",
        ),
    };
    let read = |d: &Path, f: &str| std::fs::read_to_string(d.join(f)).ok();
    let mut out = Vec::new();
    let mut d = Some(dir);
    while let Some(level) = d {
        if let (Some(limit), Some(usage)) = (
            read(level, limit_file).and_then(|t| cgroup_limit(&t)),
            read(level, usage_file).and_then(|t| t.trim().parse::<u64>().ok()),
        ) {
            let inactive = read(level, "memory.stat")
                .and_then(|t| stat_field(&t, inactive_key))
                .unwrap_or(0);
            let used = usage.saturating_sub(inactive);
            out.push(AvailableMemory {
                bytes: limit.saturating_sub(used),
                bound: MemoryBound::Cgroup {
                    dir: level.to_path_buf(),
                    limit,
                    used,
                },
            });
        }
        if level == top {
            break;
        }
        d = level.parent().filter(|p| p.starts_with(top));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn proc_files_are_read() {
        let meminfo = "MemTotal:       24000000 kB\nMemFree:  100 kB\nMemAvailable:   23918712 kB\n";
        assert_eq!(kib_field(meminfo, "MemAvailable:"), Some(23918712 * 1024));
        let status = "Name:\tdemcon\nVmPeak:\t  9000 kB\nVmSize:\t    3892 kB\n";
        assert_eq!(kib_field(status, "VmSize:"), Some(3892 * 1024));
        assert_eq!(kib_field(status, "VmRSS:"), None);
        let limits = "Limit                     Soft Limit           Hard Limit           Units     \n\
                      Max stack size            8388608              unlimited            bytes     \n\
                      Max address space         4096000000           unlimited            bytes     \n";
        assert_eq!(address_space_limit(limits), Some(4_096_000_000));
        let unlimited = "Max address space         unlimited            unlimited            bytes     \n";
        assert_eq!(address_space_limit(unlimited), None);
    }

    #[test]
    fn cgroup_limits_are_read() {
        assert_eq!(cgroup_limit("max\n"), None);
        assert_eq!(cgroup_limit("4294967296\n"), Some(4 << 30));
        // cgroup v1's "no limit" is PAGE_COUNTER_MAX pages, about 2⁶³.
        assert_eq!(cgroup_limit("9223372036854771712\n"), None);
        let stat = "cache 10\ninactive_file 687898624\ntotal_inactive_file 700000000\n";
        assert_eq!(stat_field(stat, "inactive_file"), Some(687898624));
        assert_eq!(stat_field(stat, "total_inactive_file"), Some(700000000));
        assert_eq!(stat_field(stat, "active_file"), None);
    }

    #[test]
    fn cgroup_folders_come_from_the_mounts() {
        // A hybrid machine: v1 memory controller, v2 unified without it.
        let cgroup = "9:name=systemd:/\n4:memory:/process_api/301df\n3:cpuset:/\n0::/\n";
        let mountinfo = "31 23 0:28 / /sys/fs/cgroup rw,relatime - tmpfs tmpfs rw,mode=755\n\
                         35 31 0:32 / /sys/fs/cgroup/memory rw,relatime - cgroup cgroup rw,memory\n\
                         36 31 0:33 / /sys/fs/cgroup/devices rw,relatime - cgroup cgroup rw,devices\n\
                         41 31 0:38 / /sys/fs/cgroup/unified rw,relatime - cgroup2 cgroup2 rw\n";
        assert_eq!(
            cgroup_dirs(cgroup, mountinfo),
            [
                (
                    PathBuf::from("/sys/fs/cgroup/memory/process_api/301df"),
                    PathBuf::from("/sys/fs/cgroup/memory"),
                    CgroupVersion::V1
                ),
                (
                    PathBuf::from("/sys/fs/cgroup/unified"),
                    PathBuf::from("/sys/fs/cgroup/unified"),
                    CgroupVersion::V2
                ),
            ]
        );
        // A container on v2 whose cgroup namespace root is its own cgroup.
        let mountinfo = "600 500 0:30 /docker/abc /sys/fs/cgroup ro,nosuid - cgroup2 cgroup rw\n";
        assert_eq!(
            cgroup_dirs("0::/docker/abc/worker\n", mountinfo),
            [(
                PathBuf::from("/sys/fs/cgroup/worker"),
                PathBuf::from("/sys/fs/cgroup"),
                CgroupVersion::V2
            )]
        );
        assert!(cgroup_dirs("0::/\n", "").is_empty());
    }

    /// A cgroup v2 tree on disk: the tighter of two levels bounds, page cache left out.
    #[test]
    fn the_tightest_cgroup_level_bounds() {
        let top = std::env::temp_dir().join(format!("demcon-core-cgroup-{}", std::process::id()));
        let leaf = top.join("job/step");
        std::fs::create_dir_all(&leaf).unwrap();
        let write = |d: &Path, f: &str, t: &str| std::fs::write(d.join(f), t).unwrap();
        write(&top, "memory.max", "max\n");
        write(&top, "memory.current", "100\n");
        write(&top.join("job"), "memory.max", "4000000000\n");
        write(&top.join("job"), "memory.current", "1500000000\n");
        write(
            &top.join("job"),
            "memory.stat",
            "anon 1\ninactive_file 500000000\n",
        );
        write(&leaf, "memory.max", "max\n");
        write(&leaf, "memory.current", "5\n");
        let levels = cgroup_levels(&leaf, &top, CgroupVersion::V2);
        assert_eq!(levels.len(), 1, "{levels:?}");
        let best = least(levels).unwrap();
        assert_eq!(best.bytes, 3_000_000_000);
        let said = best.bound.to_string();
        assert!(said.contains("job") && said.contains("4.000e9"), "{said}");
        let _ = std::fs::remove_dir_all(&top);
    }

    #[test]
    fn the_least_bound_wins_and_is_named() {
        let mem = AvailableMemory {
            bytes: 20 << 30,
            bound: MemoryBound::MemAvailable,
        };
        let rlimit = AvailableMemory {
            bytes: 3_900_000_000,
            bound: MemoryBound::AddressSpace {
                limit: 4_096_000_000,
                mapped: 196_000_000,
            },
        };
        let best = least(vec![mem.clone(), rlimit.clone()]).unwrap();
        assert_eq!(best, rlimit);
        assert!(best.bound.to_string().contains("RLIMIT_AS"));
        assert_eq!(least(vec![mem.clone()]), Some(mem));
        assert_eq!(least(Vec::new()), None);
    }

    /// On Linux the machine's figures are read; the result is never above MemAvailable.
    #[cfg(target_os = "linux")]
    #[test]
    fn this_machine_has_a_bound() {
        let a = available_memory_bound().unwrap();
        let meminfo = std::fs::read_to_string("/proc/meminfo").unwrap();
        assert!(a.bytes > 0 && a.bytes <= kib_field(&meminfo, "MemAvailable:").unwrap() + (1 << 30));
    }
}

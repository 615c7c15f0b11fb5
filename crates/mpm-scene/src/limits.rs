//! What the machine allows a run: the memory available to this process, the size of a scene
//! file, and the guards on particles, bodies, vertices and probes. Scenes are checked against
//! these before anything large is allocated.

/// Most particles a scene may generate (a guard against a typo such as a 1e-6 m cell, which
/// would otherwise exhaust memory before any message).
pub const MAX_PARTICLES: usize = 20_000_000;

/// Most bodies a scene may declare (the overlap check compares every pair's bounding boxes).
pub const MAX_BODIES: usize = 10_000;

/// Most vertices of a polygon (the simplicity check compares every pair of edges).
pub const MAX_VERTICES: usize = 10_000;

/// Most probes a scene may declare.
pub const MAX_PROBES: usize = 10_000;

/// Largest `particles_per_cell` (n × n per cell).
pub const MAX_PARTICLES_PER_CELL: i64 = 16;

/// Largest scene file read (bytes). Scenes are hand-written settings and outlines; 4 MiB holds a
/// profile or polygon of ~100 000 points, and parsing it peaks near 100× its size.
pub const MAX_SCENE_BYTES: u64 = 4 << 20;

/// The memory this process may still use (bytes) and where that limit comes from: the smallest
/// of the memory the kernel reports available (`MemAvailable`), half the address-space limit
/// (`ulimit -v`), the cgroup's memory limit minus its usage, and the environment variable
/// `MPM_MEMORY_LIMIT` (bytes; for tests and shared machines). `None` where none is known.
pub fn available_memory() -> Option<(u64, &'static str)> {
    let mut best: Option<(u64, &'static str)> = None;
    let mut take = |bytes: Option<u64>, source: &'static str| {
        if let Some(b) = bytes {
            if best.is_none_or(|(m, _)| b < m) {
                best = Some((b, source));
            }
        }
    };
    let read = |path: &str| std::fs::read_to_string(path).ok();
    take(
        read("/proc/meminfo").and_then(|t| field_kib(&t, "MemAvailable:")).map(|k| k * 1024),
        "available memory (/proc/meminfo)",
    );
    // Half the address-space limit: the process reserves about twice the memory it uses
    // (allocator arenas per thread, thread stacks, vectors growing by doubling; R3-02 measured
    // 900 MB of address space for 450 MB resident, and an abort under a limit of 614 MB).
    take(
        read("/proc/self/limits").and_then(|t| address_limit(&t)).map(|b| b / 2),
        "half the address-space limit (ulimit -v)",
    );
    let cgroup =
        read("/sys/fs/cgroup/memory.max").and_then(|m| m.trim().parse::<u64>().ok()).map(|max| {
            let used = read("/sys/fs/cgroup/memory.current")
                .and_then(|c| c.trim().parse::<u64>().ok())
                .unwrap_or(0);
            max.saturating_sub(used)
        });
    take(cgroup, "cgroup memory limit (/sys/fs/cgroup/memory.max)");
    take(memory_limit_env().ok().flatten(), "MPM_MEMORY_LIMIT");
    best
}

/// The environment variable `MPM_MEMORY_LIMIT`: `Ok(None)` when unset, else the bytes it
/// gives (a whole number, optionally with a binary suffix K, M, G or T: `2G` is 2 GiB), or
/// `Err` with the message a front end prints (a limit that is not understood is refused, not
/// ignored: `abc` or `-5` used to leave the run unguarded without a word).
pub fn memory_limit_env() -> Result<Option<u64>, String> {
    let Some(raw) = std::env::var_os("MPM_MEMORY_LIMIT") else { return Ok(None) };
    let text = raw.to_string_lossy();
    // `MPM_MEMORY_LIMIT=` (set to nothing) is unset, as shells and CI files write it
    if text.trim().is_empty() {
        return Ok(None);
    }
    parse_bytes(&text).map(Some).ok_or_else(|| {
        format!(
            "MPM_MEMORY_LIMIT = {text:?} is not a memory size: give a whole number of bytes, \
             optionally with a binary suffix (e.g. 2000000000 or 2G), or unset it"
        )
    })
}

/// `1234`, `512M`, `2G`, `2GiB` … as bytes; `None` for anything else, zero or an overflow.
fn parse_bytes(text: &str) -> Option<u64> {
    let t = text.trim();
    let digits = t.find(|c: char| !c.is_ascii_digit()).unwrap_or(t.len());
    let (number, suffix) = t.split_at(digits);
    let unit = suffix.trim().to_ascii_uppercase();
    let shift = match unit.trim_end_matches("IB").trim_end_matches('B') {
        "" => 0,
        "K" => 10,
        "M" => 20,
        "G" => 30,
        "T" => 40,
        _ => return None,
    };
    let n: u64 = number.parse().ok()?;
    n.checked_mul(1u64 << shift).filter(|&b| b > 0)
}

/// the value (kB) of a `/proc/meminfo` line starting with `key`.
fn field_kib(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    line[key.len()..].split_whitespace().next()?.parse().ok()
}

/// the soft "Max address space" of `/proc/self/limits` (bytes), `None` when unlimited.
fn address_limit(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..].split_whitespace().next()?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn proc_files_are_read_as_the_kernel_writes_them() {
        let meminfo = "MemTotal:       24000000 kB\nMemAvailable:   12345678 kB\n";
        assert_eq!(field_kib(meminfo, "MemAvailable:"), Some(12_345_678));
        let limits = "Limit                     Soft Limit           Hard Limit           Units\n\
                      Max address space         409600000            unlimited            bytes\n";
        assert_eq!(address_limit(limits), Some(409_600_000));
        let unlimited =
            "Max address space         unlimited            unlimited            bytes\n";
        assert_eq!(address_limit(unlimited), None);
    }

    #[test]
    fn memory_sizes_read_as_bytes_and_nonsense_is_refused() {
        assert_eq!(parse_bytes("2000000000"), Some(2_000_000_000));
        assert_eq!(parse_bytes(" 2G "), Some(2 << 30));
        assert_eq!(parse_bytes("512MiB"), Some(512 << 20));
        assert_eq!(parse_bytes("64K"), Some(64 << 10));
        assert_eq!(parse_bytes("2g"), Some(2 << 30));
        for bad in ["abc", "-5", "", "0", "1.5G", "2X", "99999999999999999999", "20000000T"] {
            assert_eq!(parse_bytes(bad), None, "{bad}");
        }
    }
}

//! The memory available to this process, from the system and `RAILUQ_MEMORY_LIMIT`.

/// Memory available to this process (bytes): the least of the system's available memory
/// (`MemAvailable` of `/proc/meminfo`), the room left under a cgroup limit
/// (`memory.max` − `memory.current`, v2; `memory.limit_in_bytes` − `memory.usage_in_bytes`,
/// v1) and the room left in the address-space limit (`ulimit -v`: `Max address space` of
/// `/proc/self/limits` − `VmSize` of `/proc/self/status`), and `RAILUQ_MEMORY_LIMIT`
/// (bytes) where set (to keep studies within a budget of one's own, or to test the guard).
/// `None` where none is known.
pub fn available_memory() -> Option<f64> {
    let read = |p: &str| std::fs::read_to_string(p).ok();
    let number = |s: Option<String>| -> Option<f64> { s?.trim().parse::<f64>().ok() };
    let kib_field = |text: &str, key: &str| -> Option<f64> {
        let line = text.lines().find(|l| l.starts_with(key))?;
        let kib: f64 = line[key.len()..].split_whitespace().next()?.parse().ok()?;
        Some(kib * 1024.0)
    };
    let mut limits = Vec::new();
    if let Some(m) = read("/proc/meminfo").and_then(|t| kib_field(&t, "MemAvailable:")) {
        limits.push(m);
    }
    for (max, used) in [
        ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
        (
            "/sys/fs/cgroup/memory/memory.limit_in_bytes",
            "/sys/fs/cgroup/memory/memory.usage_in_bytes",
        ),
    ] {
        if let (Some(m), Some(u)) = (number(read(max)), number(read(used))) {
            // "max" (no limit) does not parse; v1 reports no limit as a huge number.
            if m < 1e18 {
                limits.push((m - u).max(0.0));
            }
        }
    }
    if let Some(text) = read("/proc/self/limits") {
        let soft = text
            .lines()
            .find(|l| l.starts_with("Max address space"))
            .and_then(|l| l.split_whitespace().nth(3))
            .and_then(|v| v.parse::<f64>().ok());
        let size = read("/proc/self/status").and_then(|t| kib_field(&t, "VmSize:"));
        if let (Some(limit), Some(size)) = (soft, size) {
            limits.push((limit - size).max(0.0));
        }
    }
    if let Some(m) = std::env::var("RAILUQ_MEMORY_LIMIT")
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|m| *m >= 0.0)
    {
        limits.push(m);
    }
    limits.into_iter().reduce(f64::min)
}

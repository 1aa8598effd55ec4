//! Memory limits: how much a render may allocate for its image, grids and
//! other large buffers, checked from the declared sizes *before* anything is
//! allocated, so that a scene asking for too much gets an error naming the
//! field and the estimated size instead of being killed by the system.
//!
//! The default limit is half of the machine's memory (`MemTotal` in
//! `/proc/meminfo`; 4 GiB where that cannot be read). `niebla render
//! --max-memory 8G` overrides it.
//!
//! ```
//! use niebla::limits::{format_bytes, parse_memory_size};
//! assert_eq!(parse_memory_size("8G").unwrap(), 8 << 30);
//! assert_eq!(parse_memory_size("512MiB").unwrap(), 512 << 20);
//! assert_eq!(format_bytes(3 << 29), "1.5 GiB");
//! ```

/// The limit used where `/proc/meminfo` cannot be read: 4 GiB.
pub const FALLBACK_MEMORY_LIMIT: u64 = 4 << 30;

/// Half of the machine's physical memory (`MemTotal` in `/proc/meminfo`), or
/// [`FALLBACK_MEMORY_LIMIT`] where that file is missing or unreadable.
pub fn default_memory_limit() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|text| mem_total_bytes(&text))
        .map_or(FALLBACK_MEMORY_LIMIT, |total| total / 2)
}

/// `MemTotal` of a `/proc/meminfo` text, in bytes.
fn mem_total_bytes(meminfo: &str) -> Option<u64> {
    let line = meminfo.lines().find(|l| l.starts_with("MemTotal:"))?;
    let mut words = line["MemTotal:".len()..].split_whitespace();
    let value: u64 = words.next()?.parse().ok()?;
    let unit = match words.next() {
        Some("kB") | Some("KB") | Some("kiB") => 1024,
        None => 1,
        Some(_) => return None,
    };
    value.checked_mul(unit)
}

/// Parses a memory size: a number with an optional binary unit suffix `K`,
/// `M`, `G` or `T` (powers of 1024; `KB`/`KiB` and the like mean the same),
/// e.g. `8G`, `1.5GiB`, `512M`, `1000000` (bytes). Errors say what was
/// expected.
pub fn parse_memory_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
    let (number, unit) = (t[..split].trim(), t[split..].trim());
    let scale: u64 = match unit.to_ascii_uppercase().as_str() {
        "" | "B" => 1,
        "K" | "KB" | "KIB" => 1 << 10,
        "M" | "MB" | "MIB" => 1 << 20,
        "G" | "GB" | "GIB" => 1 << 30,
        "T" | "TB" | "TIB" => 1 << 40,
        _ => return Err(format!("expected a size such as 8G, 512M or 1000000 (bytes), got {text:?}")),
    };
    let value: f64 =
        number.parse().map_err(|_| format!("expected a size such as 8G, 512M or 1000000 (bytes), got {text:?}"))?;
    let bytes = value * scale as f64;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < 2f64.powi(63)) {
        return Err(format!("expected a size of at least 1 byte and below 8 EiB, got {text:?}"));
    }
    Ok(bytes as u64)
}

/// A byte count for messages: `512 B`, `3.2 MiB`, `1.5 GiB`.
pub fn format_bytes(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["KiB", "MiB", "GiB", "TiB", "PiB"];
    if bytes < 1024 {
        return format!("{bytes} B");
    }
    let mut value = bytes as f64 / 1024.0;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    let digits = if value < 10.0 { 1 } else { 0 };
    let text = format!("{value:.digits$}");
    let text = text.strip_suffix(".0").unwrap_or(&text);
    format!("{text} {}", UNITS[unit])
}

/// A memory budget that large allocations are charged against before they
/// happen.
///
/// ```
/// use niebla::limits::MemoryBudget;
/// let mut budget = MemoryBudget::new(1 << 20);
/// assert!(budget.charge(512 << 10).is_ok());
/// let err = budget.charge(768 << 10).unwrap_err();
/// assert_eq!(err, "would need about 768 KiB, but only 512 KiB of the memory limit of 1 MiB are left");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryBudget {
    /// The whole limit, in bytes.
    pub limit: u64,
    /// Bytes charged so far.
    pub used: u64,
}

impl MemoryBudget {
    /// A budget of `limit` bytes, nothing used.
    pub fn new(limit: u64) -> MemoryBudget {
        MemoryBudget { limit, used: 0 }
    }

    /// Bytes still available.
    pub fn left(&self) -> u64 {
        self.limit.saturating_sub(self.used)
    }

    /// Charges `bytes`, or explains (without charging) why they do not fit:
    /// the estimated size and what is left of the limit.
    pub fn charge(&mut self, bytes: u64) -> Result<(), String> {
        if bytes <= self.left() {
            self.used += bytes;
            return Ok(());
        }
        if self.used == 0 {
            return Err(format!(
                "would need about {}, over the memory limit of {}",
                format_bytes(bytes),
                format_bytes(self.limit)
            ));
        }
        Err(format!(
            "would need about {}, but only {} of the memory limit of {} are left",
            format_bytes(bytes),
            format_bytes(self.left()),
            format_bytes(self.limit)
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_units() {
        assert_eq!(parse_memory_size("1000000"), Ok(1_000_000));
        assert_eq!(parse_memory_size("64k"), Ok(64 << 10));
        assert_eq!(parse_memory_size(" 2 GB "), Ok(2 << 30));
        assert_eq!(parse_memory_size("0.5T"), Ok(1 << 39));
        for bad in ["", "G", "-1G", "0", "8X", "nanG", "1e30T"] {
            assert!(parse_memory_size(bad).is_err(), "{bad:?} accepted");
        }
    }

    #[test]
    fn meminfo_total_is_read_in_kibibytes() {
        let text = "MemTotal:       24684092 kB\nMemFree:        20974524 kB\n";
        assert_eq!(mem_total_bytes(text), Some(24684092 * 1024));
        assert_eq!(mem_total_bytes("MemFree: 1 kB"), None);
        assert!(default_memory_limit() > 0);
    }

    #[test]
    fn budget_refuses_without_charging() {
        let mut b = MemoryBudget::new(100);
        assert!(b.charge(60).is_ok());
        assert!(b.charge(60).is_err());
        assert_eq!(b.used, 60);
        assert!(b.charge(40).is_ok());
        assert_eq!(b.left(), 0);
        assert_eq!(format_bytes(100), "100 B");
        assert_eq!(format_bytes(12 << 30), "12 GiB");
    }
}

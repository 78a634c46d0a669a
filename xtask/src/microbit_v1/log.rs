//! The figures the v1's firmware logs: its RAM, watchdog and per-level frame
//! costs, and where its flash goes (its CPU load is read as every board's,
//! [`crate::demo::parse_cpu_load`]).

/// `ram: statics S B + stack high-water H B = T B …` → (statics, stack).
pub fn parse_ram(log: &str) -> Option<(u64, u64)> {
    log.lines().find_map(|line| {
        let rest = &line[line.find("ram: statics ")? + "ram: statics ".len()..];
        let (statics, rest) = rest.split_once(" B + stack high-water ")?;
        let (stack, _) = rest.split_once(" B")?;
        Some((statics.parse().ok()?, stack.parse().ok()?))
    })
}

/// Code bytes per crate and top module (`marble_rolling::physics`,
/// `core::fmt`, …), largest first: where the flash goes.
pub fn bloat(elf: &[u8]) -> Result<Vec<(String, u64)>, String> {
    let mut totals: std::collections::BTreeMap<String, u64> = std::collections::BTreeMap::new();
    for symbol in crate::symbols::code_symbols(elf)? {
        let name = crate::symbols::readable(&symbol.mangled);
        *totals.entry(module_of(&name)).or_default() += symbol.size;
    }
    let mut list: Vec<(String, u64)> = totals.into_iter().collect();
    list.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
    Ok(list)
}

/// The first two path segments of a demangled name (the type's, for an
/// `<impl …>` or `<T as Trait>` name).
pub fn module_of(name: &str) -> String {
    let name = name.trim_start_matches('<').trim_start_matches("impl ");
    let path: String = name
        .chars()
        .take_while(|&c| c.is_alphanumeric() || c == '_' || c == ':')
        .collect();
    let mut segments = path.split("::").filter(|s| !s.is_empty());
    match (segments.next(), segments.next()) {
        (Some(first), Some(second)) => format!("{first}::{second}"),
        (Some(first), None) if path.contains("::") => first.to_string(),
        _ => "(symbols without a path: vectors, handlers, builtins)".to_string(),
    }
}

/// `watchdog: longest wait without a pet W ms (it resets at R ms)` → (W, R).
pub fn parse_watchdog(log: &str) -> Option<(u64, u64)> {
    log.lines().find_map(|line| {
        let rest = &line
            [line.find("longest wait without a pet ")? + "longest wait without a pet ".len()..];
        let (waited, rest) = rest.split_once(" ms (it resets at ")?;
        let (resets_at, _) = rest.split_once(" ms")?;
        Some((waited.parse().ok()?, resets_at.parse().ok()?))
    })
}

/// `profile LEVEL: N frames, instructions per frame: physics AVG (max MAX),
/// …` → (level, frames, average, max).
pub fn parse_profile(line: &str) -> Option<(String, u32, u64, u64)> {
    let rest = &line[line.find("profile ")? + "profile ".len()..];
    let (level, rest) = rest.split_once(": ")?;
    let (frames, rest) = rest.split_once(" frames, instructions per frame: physics ")?;
    let (average, rest) = rest.split_once(" (max ")?;
    let (max, _) = rest.split_once(')')?;
    Some((
        level.to_string(),
        frames.parse().ok()?,
        average.parse().ok()?,
        max.parse().ok()?,
    ))
}

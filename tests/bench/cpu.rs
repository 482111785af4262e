//! The CPU time of the bench process, shared by the benches that print it.

/// CPU time (user + system) of this process so far, from /proc/self/stat (clock ticks of
/// 1/100 s); NaN where that file does not exist.
pub fn cpu_s() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    let Some(rest) = stat.rsplit(')').next() else {
        return f64::NAN;
    };
    let f: Vec<&str> = rest.split_whitespace().collect();
    // after the command: state is field 3, utime 14 and stime 15 (1-based over the whole line)
    let tick = |i: usize| f.get(i - 3).and_then(|x| x.parse::<f64>().ok());
    match (tick(14), tick(15)) {
        (Some(u), Some(s)) => (u + s) / 100.0,
        _ => f64::NAN,
    }
}

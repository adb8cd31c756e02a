//! Criterion benchmarks live in `benches/`; the measuring examples in `examples/`. This library holds what
//! they share for timing: process CPU time, quartiles of repeated measurements and the machine's load average
//! (every figure quoted in README carries the load it was measured at).

/// CPU seconds this process has used (user + system: fields 14 and 15 of `/proc/self/stat`, 100 clock ticks
/// per second on Linux); 0 where unavailable.
pub fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            // Fields after the parenthesised command name (which may itself hold spaces or parentheses).
            let rest = s.rsplit(')').next()?.to_string();
            let f: Vec<&str> = rest.split_whitespace().collect();
            Some((f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?) / 100.0)
        })
        .unwrap_or(0.0)
}

/// Positional argument `i` of an example's command line (`args`: the arguments after the program name),
/// parsed as `T`, or `default` when absent; a value that does not parse ends the program with exit code 2 and a
/// message naming the position and the value.
pub fn arg<T: std::str::FromStr>(args: &[String], i: usize, default: T) -> T {
    match args.get(i) {
        None => default,
        Some(s) => s.parse().unwrap_or_else(|_| {
            eprintln!(
                "argument {} ({s:?}) is not a number of the expected kind",
                i + 1
            );
            std::process::exit(2)
        }),
    }
}

/// Lower quartile, median and upper quartile of `v` (nearest-rank on the sorted values); `v` must not be
/// empty.
pub fn quartiles(mut v: Vec<f64>) -> [f64; 3] {
    v.sort_by(f64::total_cmp);
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    [q(0.25), q(0.5), q(0.75)]
}

/// The 1-, 5- and 15-minute load averages, as `/proc/loadavg` gives them (empty where unavailable).
pub fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arg_parses_the_given_position_or_takes_the_default() {
        let args = vec!["12".to_string(), "0.5".to_string()];
        assert_eq!(arg(&args, 0, 7usize), 12);
        assert_eq!(arg(&args, 1, 0.0f64), 0.5);
        assert_eq!(arg(&args, 2, 9usize), 9);
    }

    #[test]
    fn quartiles_of_nine_values_are_the_third_fifth_and_seventh() {
        let v = vec![9.0, 1.0, 8.0, 2.0, 7.0, 3.0, 6.0, 4.0, 5.0];
        assert_eq!(quartiles(v), [3.0, 5.0, 7.0]);
        assert_eq!(quartiles(vec![4.0]), [4.0; 3]);
    }

    /// Busy work until the counter advances (a 10 ms tick), capped at 30 s of wall time so a counter that
    /// never moves fails instead of hanging; independent of the machine's load.
    #[test]
    fn cpu_time_grows_with_work() {
        if !std::path::Path::new("/proc/self/stat").exists() {
            return;
        }
        let before = cpu_seconds();
        let start = std::time::Instant::now();
        let mut x = 0.0f64;
        while cpu_seconds() <= before && start.elapsed().as_secs_f64() < 30.0 {
            for _ in 0..100_000 {
                x = std::hint::black_box(x + 1.0).sqrt();
            }
        }
        assert!(x.is_finite());
        assert!(
            cpu_seconds() > before,
            "process CPU time did not advance in 30 s of busy work"
        );
    }
}

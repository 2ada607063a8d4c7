//! Frame timing shared by `compare` and `bench`: warm-up frames, then timed frames, summarised.

/// Median, minimum and maximum of the timed frames, in milliseconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameTimes {
    /// Median.
    pub median: f64,
    /// Fastest frame.
    pub min: f64,
    /// Slowest frame.
    pub max: f64,
}

/// Runs `frame` `warm_up` times untimed, then `frames` times (at least once); `frame` returns
/// its own duration in milliseconds (the renderer's [`refract_scene::FrameTiming`]).
pub fn time_frames(
    warm_up: u32,
    frames: u32,
    mut frame: impl FnMut() -> crate::Result<f64>,
) -> crate::Result<FrameTimes> {
    for _ in 0..warm_up {
        frame()?;
    }
    let mut times = (0..frames.max(1))
        .map(|_| frame())
        .collect::<crate::Result<Vec<f64>>>()?;
    times.sort_by(f64::total_cmp);
    Ok(FrameTimes {
        median: times[times.len() / 2],
        min: times[0],
        max: times[times.len() - 1],
    })
}

/// `repeats` rounds of [`time_frames`] of configuration 0, then configuration 1, alternating so
/// that a drift of the machine (heat, another process) reaches both alike: `frame(k)` renders
/// one frame of configuration `k` and returns its milliseconds. One `(times of 0, times of 1)`
/// pair per round.
pub fn alternating(
    repeats: u32,
    warm_up: u32,
    frames: u32,
    mut frame: impl FnMut(usize) -> crate::Result<f64>,
) -> crate::Result<Vec<(FrameTimes, FrameTimes)>> {
    (0..repeats.max(1))
        .map(|_| {
            let a = time_frames(warm_up, frames, || frame(0))?;
            let b = time_frames(warm_up, frames, || frame(1))?;
            Ok((a, b))
        })
        .collect()
}

/// The smallest, median and largest of `values` (empty: `None`).
pub fn spread(values: &[f64]) -> Option<(f64, f64, f64)> {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    Some((*v.first()?, v[v.len() / 2], *v.last()?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warm_up_frames_are_not_timed() {
        let mut calls = 0.0;
        let times = time_frames(2, 3, || {
            calls += 1.0;
            Ok(calls)
        })
        .expect("times");
        assert_eq!(
            times,
            FrameTimes {
                median: 4.0,
                min: 3.0,
                max: 5.0
            }
        );
    }

    /// Rounds alternate the two configurations, each timed after its own warm-up.
    #[test]
    fn rounds_alternate_the_configurations() {
        let mut order = Vec::new();
        let rounds = alternating(2, 1, 2, |k| {
            order.push(k);
            Ok(10.0 * (k as f64 + 1.0))
        })
        .expect("rounds");
        assert_eq!(order, [0, 0, 0, 1, 1, 1, 0, 0, 0, 1, 1, 1]);
        assert_eq!(rounds.len(), 2);
        assert_eq!((rounds[0].0.median, rounds[0].1.median), (10.0, 20.0));
        assert_eq!(spread(&[3.0, 1.0, 2.0]), Some((1.0, 2.0, 3.0)));
        assert_eq!(spread(&[]), None);
    }
}

/// The CPU the timings ran on, read from the system, not typed: its model (from
/// `/proc/cpuinfo`, `unknown CPU` where that cannot be read) and the threads the CPU backend
/// uses (rayon's pool), e.g. `AMD EPYC 7B13, 2 threads`.
pub fn cpu_description() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|text| {
            text.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, name)| name.split_whitespace().collect::<Vec<_>>().join(" "))
        })
        .filter(|name| !name.is_empty())
        .unwrap_or_else(|| "unknown CPU".to_owned());
    let threads = rayon::current_num_threads();
    format!(
        "{model}, {threads} thread{}",
        if threads == 1 { "" } else { "s" }
    )
}

#[cfg(test)]
mod machine_tests {
    /// The description names the thread count rayon really uses.
    #[test]
    fn the_cpu_description_is_measured() {
        let text = super::cpu_description();
        assert!(
            text.ends_with(&format!("{} threads", rayon::current_num_threads()))
                || text.ends_with("1 thread"),
            "{text}"
        );
        assert!(!text.starts_with(','), "{text}");
    }
}

//! Frame timing shared by `compare` and `bench`: warm-up frames, then timed frames, summarised.

use std::time::Instant;

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
/// its own duration in milliseconds (GPU timestamps, or [`wall_ms`]).
pub fn time_frames(
    warm_up: u32,
    frames: u32,
    mut frame: impl FnMut() -> anyhow::Result<f64>,
) -> anyhow::Result<FrameTimes> {
    for _ in 0..warm_up {
        frame()?;
    }
    let mut times = (0..frames.max(1))
        .map(|_| frame())
        .collect::<anyhow::Result<Vec<f64>>>()?;
    times.sort_by(f64::total_cmp);
    Ok(FrameTimes {
        median: times[times.len() / 2],
        min: times[0],
        max: times[times.len() - 1],
    })
}

/// Wall-clock milliseconds of one call of `work`.
pub fn wall_ms(work: impl FnOnce() -> anyhow::Result<()>) -> anyhow::Result<f64> {
    let start = Instant::now();
    work()?;
    Ok(start.elapsed().as_secs_f64() * 1e3)
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
}

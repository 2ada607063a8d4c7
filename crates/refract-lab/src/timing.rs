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

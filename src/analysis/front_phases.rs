//! The three phases of a granular front on a slope (Martin et al. 2022,
//! section 5.1.1, after Mangeney et al. 2010 and Farin et al. 2014): it
//! accelerates to its largest speed, decelerates, then (on slopes, the
//! more so on an erodible bed) goes on at a slow, roughly steady speed
//! before it stops.
//!
//! From the front's position r_f(t), sampled at increasing times:
//!
//! - the front speed v_f is the central difference of r_f, averaged over a
//!   window of `smoothing` seconds (the front advances grain by grain);
//! - the acceleration ends at the largest v_f;
//! - the front stops when v_f falls below the rest speed for good (and
//!   stays there three smoothing windows at least before the run ends);
//! - the deceleration ends at the knee of v_f between its maximum and the
//!   stop (or the end of the run): the sample farthest below the chord
//!   that joins them;
//! - the slow phase runs from the knee to the stop. It is present when it
//!   lasts at least three smoothing windows, its mean speed (its distance
//!   over its duration) is above twice the rest speed, and the mean speeds
//!   of its two halves agree within a factor of two: a front that goes on
//!   at a steady speed, not one whose speed keeps falling (a deceleration
//!   at a constant rate leaves no knee; an exponential decay halves its
//!   speed again and again).

/// The phases of one front; times after the release (s), speeds (m/s).
#[derive(Debug, Clone, PartialEq)]
pub struct FrontPhases {
    /// v_f at each sample.
    pub speed: Vec<f64>,
    pub max_speed: f64,
    pub max_speed_time: f64,
    /// The knee that ends the deceleration, where there is one.
    pub deceleration_end_time: Option<f64>,
    pub slow_phase: bool,
    /// Mean speed from the knee to the stop (or the end of the run).
    pub slow_phase_speed: Option<f64>,
    /// When the front came to rest for good; `None` while it still moves.
    pub stop_time: Option<f64>,
}

/// The phases of the front `front` sampled at `times`, with v_f averaged
/// over `smoothing` seconds and `rest_speed` the speed below which the
/// front is at rest.
pub fn front_phases(times: &[f64], front: &[f64], smoothing: f64, rest_speed: f64) -> FrontPhases {
    let n = times.len();
    let speed = smoothed_speed(times, front, smoothing);
    let none = FrontPhases {
        speed: speed.clone(),
        max_speed: 0.0,
        max_speed_time: times.first().copied().unwrap_or(0.0),
        deceleration_end_time: None,
        slow_phase: false,
        slow_phase_speed: None,
        stop_time: None,
    };
    if n < 3 {
        return none;
    }
    let top = (0..n)
        .max_by(|&a, &b| speed[a].total_cmp(&speed[b]))
        .unwrap();
    // From the stop on, v_f stays below the rest speed, for three
    // smoothing windows at least (a front that paused as the run ended
    // may go on).
    let stop = (top..n)
        .rev()
        .take_while(|&k| speed[k] < rest_speed)
        .last()
        .filter(|&k| times[n - 1] - times[k] >= 3.0 * smoothing);
    let end = stop.unwrap_or(n - 1);
    let mut phases = FrontPhases {
        max_speed: speed[top],
        max_speed_time: times[top],
        stop_time: stop.map(|k| times[k]),
        ..none
    };
    if end <= top + 1 {
        return phases;
    }
    let chord = |k: usize| {
        speed[top] + (speed[end] - speed[top]) * (times[k] - times[top]) / (times[end] - times[top])
    };
    let (knee, below) = (top + 1..end)
        .map(|k| (k, chord(k) - speed[k]))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    if below <= 0.0 {
        return phases;
    }
    phases.deceleration_end_time = Some(times[knee]);
    let mean = |a: usize, b: usize| (front[b] - front[a]) / (times[b] - times[a]);
    let slow = mean(knee, end);
    phases.slow_phase_speed = Some(slow);
    let middle = (knee..=end)
        .find(|&k| times[k] >= 0.5 * (times[knee] + times[end]))
        .unwrap_or(end);
    let lasting = times[end] - times[knee] >= 3.0 * smoothing;
    let steady = middle > knee && middle < end && {
        let (first, second) = (mean(knee, middle), mean(middle, end));
        first > 0.0 && second > 0.0 && first.max(second) <= 2.0 * first.min(second)
    };
    phases.slow_phase = lasting && slow > 2.0 * rest_speed && steady;
    phases
}

/// v_f: central differences of `front` (one-sided at the ends), averaged
/// over the samples within half of `smoothing` of each.
fn smoothed_speed(times: &[f64], front: &[f64], smoothing: f64) -> Vec<f64> {
    let n = times.len();
    if n < 2 {
        return vec![0.0; n];
    }
    let raw: Vec<f64> = (0..n)
        .map(|k| {
            let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
            (front[b] - front[a]) / (times[b] - times[a])
        })
        .collect();
    let half = 0.5 * smoothing;
    (0..n)
        .map(|k| {
            let window: Vec<f64> = (0..n)
                .filter(|&j| (times[j] - times[k]).abs() <= half + 1e-12)
                .map(|j| raw[j])
                .collect();
            window.iter().sum::<f64>() / window.len() as f64
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples every 10 ms of a front whose speed is `speed(t)` over
    /// [0, `until`], integrated by the trapezoidal rule.
    fn front_of(speed: impl Fn(f64) -> f64, until: f64) -> (Vec<f64>, Vec<f64>) {
        let dt = 0.01;
        let n = (until / dt).round() as usize + 1;
        let times: Vec<f64> = (0..n).map(|k| k as f64 * dt).collect();
        let mut front = vec![0.2];
        for k in 1..n {
            let step = 0.5 * (speed(times[k - 1]) + speed(times[k])) * dt;
            front.push(front[k - 1] + step);
        }
        (times, front)
    }

    #[test]
    fn a_front_on_a_slope_accelerates_decelerates_then_goes_on_slowly() {
        // Up to 1.6 m/s at 0.3 s, down to 0.2 m/s at 1 s, then 0.2 m/s
        // with ±10 % fluctuations until 4 s (the paper's 22°, h_i = 10 mm).
        let speed = |t: f64| {
            if t < 0.3 {
                1.6 * t / 0.3
            } else if t < 1.0 {
                1.6 - 1.4 * (t - 0.3) / 0.7
            } else {
                0.2 * (1.0 + 0.1 * (20.0 * t).sin())
            }
        };
        let (times, front) = front_of(speed, 4.0);
        let phases = front_phases(&times, &front, 0.05, 0.01);
        assert!((phases.max_speed_time - 0.3).abs() <= 0.03, "{phases:?}");
        assert!((phases.max_speed / 1.6 - 1.0).abs() < 0.05);
        let knee = phases.deceleration_end_time.unwrap();
        assert!((knee - 1.0).abs() <= 0.05, "knee at {knee}");
        assert!(phases.slow_phase);
        let slow = phases.slow_phase_speed.unwrap();
        assert!((slow / 0.2 - 1.0).abs() < 0.02, "slow speed {slow}");
        assert_eq!(phases.stop_time, None);
        // Paused for the last 0.1 s of the run: not stopped.
        let mut paused = front.clone();
        let held = paused.len() - 11;
        paused[held..].fill(front[held]);
        let phases = front_phases(&times, &paused, 0.05, 0.01);
        assert_eq!(phases.stop_time, None);
    }

    #[test]
    fn a_front_on_a_flat_bed_stops_without_a_slow_phase() {
        // Up to 1.2 m/s at 0.25 s, a constant deceleration to rest at 1 s,
        // at rest until 2 s.
        let speed = |t: f64| {
            if t < 0.25 {
                1.2 * t / 0.25
            } else {
                (1.2 * (1.0 - (t - 0.25) / 0.75)).max(0.0)
            }
        };
        let (times, front) = front_of(speed, 2.0);
        let phases = front_phases(&times, &front, 0.05, 0.01);
        assert!(!phases.slow_phase, "{:?}", phases.slow_phase_speed);
        let stop = phases.stop_time.unwrap();
        assert!((stop - 1.0).abs() <= 0.03, "stop at {stop}");
    }

    #[test]
    fn a_speed_that_keeps_halving_is_no_slow_phase() {
        // An exponential decay from 1.5 m/s (τ = 0.3 s) over 3 s.
        let (times, front) = front_of(|t| 1.5 * (-t / 0.3f64).exp(), 3.0);
        let phases = front_phases(&times, &front, 0.05, 0.001);
        assert!(phases.deceleration_end_time.is_some());
        assert!(!phases.slow_phase, "{:?}", phases.slow_phase_speed);
    }
}

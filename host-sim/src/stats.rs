//! Sample statistics shared by the experiment, the report, the bench and the bake: median,
//! mean and quartiles (linear interpolation between order statistics, as numpy's default).

/// Median of a sample (`None` if empty); sorts `v`.
pub fn median(v: &mut [f64]) -> Option<f64> {
    quantile(v, 0.5)
}

/// The `q`-quantile of a sample (`None` if empty); sorts `v`.
pub fn quantile(v: &mut [f64], q: f64) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let h = (v.len() - 1) as f64 * q.clamp(0.0, 1.0);
    let (lo, hi) = (h.floor() as usize, h.ceil() as usize);
    let (a, b) = (v[lo], v[hi]);
    Some(if lo == hi || a == b {
        a
    } else {
        a + (h - lo as f64) * (b - a)
    })
}

/// Mean of a sample (`None` if empty).
pub fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// Median, quartiles and mean of a sample (all `None` when it is empty).
pub struct Spread {
    pub q1: Option<f64>,
    pub median: Option<f64>,
    pub q3: Option<f64>,
    pub mean: Option<f64>,
}

impl Spread {
    /// The spread of `v`.
    pub fn of(mut v: Vec<f64>) -> Self {
        Self {
            mean: mean(&v),
            q1: quantile(&mut v, 0.25),
            median: quantile(&mut v, 0.5),
            q3: quantile(&mut v, 0.75),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_and_quartiles() {
        assert_eq!(median(&mut []), None);
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(quantile(&mut [1.0, 2.0, 3.0, 4.0, 5.0], 0.25), Some(2.0));
        assert_eq!(quantile(&mut [1.0, 2.0, 3.0, 4.0], 0.75), Some(3.25));
        assert_eq!(
            median(&mut [1.0, f64::INFINITY, f64::INFINITY]),
            Some(f64::INFINITY)
        );
        assert_eq!(mean(&[1.0, 2.0]), Some(1.5));
    }
}

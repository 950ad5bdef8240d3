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

/// Two-sided p-value of the Mann-Whitney U test (Wilcoxon rank-sum) that samples `a` and `b`
/// come from the same distribution: the normal approximation of U with the tie correction and
/// a continuity correction (good from about 8 values a side; the report's cells hold 5-25).
/// `None` when a sample is empty or every value is the same.
pub fn mann_whitney_p(a: &[f64], b: &[f64]) -> Option<f64> {
    let (n1, n2) = (a.len() as f64, b.len() as f64);
    if a.is_empty() || b.is_empty() {
        return None;
    }
    // Ranks of the pooled sample, ties sharing their mean rank.
    let mut all: Vec<(f64, bool)> = a
        .iter()
        .map(|&v| (v, true))
        .chain(b.iter().map(|&v| (v, false)))
        .collect();
    all.sort_by(|x, y| x.0.total_cmp(&y.0));
    let n = all.len();
    let (mut rank_a, mut ties, mut i) = (0.0, 0.0, 0);
    while i < n {
        let mut j = i;
        while j + 1 < n && all[j + 1].0 == all[i].0 {
            j += 1;
        }
        let t = (j - i + 1) as f64;
        let r = (i + j) as f64 / 2.0 + 1.0;
        rank_a += r * all[i..=j].iter().filter(|x| x.1).count() as f64;
        ties += t * t * t - t;
        i = j + 1;
    }
    let u = rank_a - n1 * (n1 + 1.0) / 2.0;
    let nn = n1 + n2;
    let var = n1 * n2 / 12.0 * ((nn + 1.0) - ties / (nn * (nn - 1.0)));
    if var <= 0.0 {
        return None;
    }
    let z = ((u - n1 * n2 / 2.0).abs() - 0.5).max(0.0) / var.sqrt();
    Some(libm::erfc(z / std::f64::consts::SQRT_2).min(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mann_whitney_tells_noise_from_a_shift() {
        // The same sample twice: no evidence of a difference.
        let a = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0];
        assert!(mann_whitney_p(&a, &a).unwrap() > 0.9);
        // Disjoint samples of 10: U = 0, z = 3.74, p = 0.00018 (scipy: mannwhitneyu(...,
        // method="asymptotic") gives 0.000183).
        let b: Vec<f64> = a.iter().map(|v| v + 20.0).collect();
        let p = mann_whitney_p(&a, &b).unwrap();
        assert!((p - 0.000183).abs() < 2e-5, "{p}");
        // Ties throughout: undefined.
        assert_eq!(mann_whitney_p(&[1.0, 1.0], &[1.0]), None);
        assert_eq!(mann_whitney_p(&[], &[1.0]), None);
    }

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

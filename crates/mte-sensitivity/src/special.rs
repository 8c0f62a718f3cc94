//! Special functions: error function, standard normal density, CDF and quantile.
//!
//! One shared copy: `erf`, `erfc`, `norm_pdf`, `norm_cdf`, `norm_ppf` and `norm_ppf_fast` are
//! [`mte_linalg::stats`]'s functions under the names this crate has always used
//! (`normal_pdf`, `normal_cdf`, `normal_quantile`, `normal_quantile_fast` there).
//!
//! ```
//! use mte_sensitivity::special::{erf, norm_cdf, norm_ppf};
//! assert!((erf(1.0) - 0.842_700_792_949_714_9).abs() < 1e-15);
//! assert!((norm_cdf(1.96) - 0.975_002_104_851_779_5).abs() < 1e-15);
//! assert!((norm_ppf(0.975) - 1.959_963_984_540_054).abs() < 1e-14);
//! ```

pub use mte_linalg::stats::{
    erf, erfc, normal_cdf as norm_cdf, normal_pdf as norm_pdf, normal_quantile as norm_ppf,
    normal_quantile_fast as norm_ppf_fast,
};

#[cfg(test)]
mod tests {
    use super::*;

    // Reference values: Abramowitz & Stegun tables / any CAS (erf(0.5), erf(1), erfc(3), Φ(−5)).
    #[test]
    fn erf_reference_values() {
        assert!((erf(0.5) - 0.520_499_877_813_046_5).abs() < 1e-15);
        assert!((erf(-1.0) + 0.842_700_792_949_714_9).abs() < 1e-15);
        assert!((erfc(3.0) / 2.209_049_699_858_544e-5 - 1.0).abs() < 1e-12);
        assert!((norm_cdf(-5.0) / 2.866_515_718_791_939e-7 - 1.0).abs() < 1e-12);
        assert!((erf(2.4999) - (1.0 - erfc(2.4999))).abs() < 1e-15);
    }

    #[test]
    fn ppf_inverts_cdf() {
        for i in 1..1000 {
            let p = i as f64 / 1000.0;
            let z = norm_ppf(p);
            assert!((norm_cdf(z) - p).abs() < 1e-15, "p = {p}");
            let zf = norm_ppf_fast(p);
            assert!((zf - z).abs() < 1e-8 * z.abs().max(1.0), "p = {p}");
        }
        assert!((norm_ppf(1e-10) + 6.361_340_902_404_056).abs() < 1e-9);
    }
}

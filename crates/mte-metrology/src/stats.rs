//! Distribution functions for the σ₀ test and coverage intervals: the workspace's shared
//! implementations in [`mte_linalg::stats`], re-exported under the names this crate has used.

pub use mte_linalg::stats::{
    chi2_cdf, chi2_quantile, erfc, gamma_p, ln_gamma, normal_cdf, normal_quantile,
};

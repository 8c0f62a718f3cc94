//! The diagnosis as Markdown: what the model gets wrong, the named cause, the gain — readable by
//! an engineer in a minute.

use std::fmt::Write;

use crate::engine::Diagnosis;
use crate::term::{Quantity, significant_decimals};

/// An RMS, maximum or noise level of the observations as engineers quote it: µm for lengths,
/// arcsec for angles (a rotary axis' positioning deviations).
fn level(q: Quantity, v: f64) -> String {
    let (v, unit) = match q {
        Quantity::Angle => ((v.to_degrees() * 3600.0), "″"),
        _ => (v * 1e3, " µm"),
    };
    format!(
        "{:.*}{unit}",
        significant_decimals(v.abs() / 10.0).min(3),
        v
    )
}

/// A p-value as text: "p = 0.012", "p = 3.1e-5", "p < 1e-12".
fn p_text(p: f64) -> String {
    if p < 1e-12 {
        "p < 1e-12".into()
    } else if p < 1e-3 {
        format!("p = {p:.1e}")
    } else {
        format!("p = {p:.3}")
    }
}

/// Renders the diagnosis as Markdown. `title` names the dataset.
pub fn markdown(d: &Diagnosis, title: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Model-discrepancy diagnosis: {title}\n");
    let noise = d
        .stated_noise
        .map(|n| format!("stated noise {}", level(d.quantity, n)))
        .unwrap_or_else(|| "no noise stated".into());
    let _ = writeln!(
        s,
        "{} observations ({}), {} {}{}, {noise}.\n",
        d.observations,
        d.channels.join(", "),
        d.setups.len(),
        d.setup_kind,
        if d.setups.len() == 1 { "" } else { "s" }
    );
    let _ = writeln!(s, "## Verdict\n");
    if d.no_discrepancy() {
        let _ = writeln!(
            s,
            "**No significant discrepancy.** The base model explains the data to the noise: held-out RMS {}, σ0 = {:.2}{}.\n",
            level(d.quantity, d.base.held_out_rms),
            d.base.sigma0,
            d.base
                .chi2_p_value
                .map(|p| format!(" (χ² test {})", p_text(p)))
                .unwrap_or_default()
        );
    } else {
        for f in &d.findings {
            let est: Vec<String> = f
                .estimates
                .iter()
                .map(|e| format!("{} = {}", e.name, e.text))
                .collect();
            let _ = writeln!(s, "- **{}** — {}: {}.", f.name, f.label, est.join(", "));
            let _ = writeln!(s, "  {}.", f.meaning);
            let _ = writeln!(
                s,
                "  Held-out RMS {} → {} ({}).",
                level(d.quantity, f.held_out_rms_before),
                level(d.quantity, f.held_out_rms_after),
                p_text(f.p_value)
            );
            if !f.alternatives.is_empty() {
                let _ = writeln!(
                    s,
                    "  Not separable with this data from: {}.{}",
                    f.alternatives.join(", "),
                    f.separated_by
                        .as_ref()
                        .map(|h| format!(" To separate them: {h}."))
                        .unwrap_or_default()
                );
            }
        }
        let _ = writeln!(
            s,
            "\n**Gain on data the fit did not see:** held-out RMS {} → {}, held-out maximum {} → {}.\n",
            level(d.quantity, d.base.held_out_rms),
            level(d.quantity, d.extended.held_out_rms),
            level(d.quantity, d.base.held_out_max_abs),
            level(d.quantity, d.extended.held_out_max_abs)
        );
        if let Some(p) = d.extended.chi2_p_value {
            let consistent = if p > 0.01 {
                "consistent with"
            } else {
                "still above"
            };
            let _ = writeln!(
                s,
                "Residuals of the extended model are {consistent} the stated noise (σ0 = {:.2}, χ² test {}).\n",
                d.extended.sigma0,
                p_text(p)
            );
        }
    }
    let _ = writeln!(s, "## Base model\n");
    let _ = writeln!(s, "| quality | fit | held out |\n|---|---|---|");
    let _ = writeln!(
        s,
        "| RMS | {} | {} |",
        level(d.quantity, d.base.rms),
        level(d.quantity, d.base.held_out_rms)
    );
    let _ = writeln!(
        s,
        "| max | {} | {} |\n",
        level(d.quantity, d.base.max_abs),
        level(d.quantity, d.base.held_out_max_abs)
    );
    let _ = writeln!(s, "| parameter | estimate ± u |\n|---|---|");
    for p in &d.base_parameters {
        for e in &p.estimates {
            let _ = writeln!(s, "| {} | {} |", e.name, e.text);
        }
    }
    let _ = writeln!(
        s,
        "\nResidual RMS per {}: {}.",
        d.setup_kind,
        per(d.quantity, &d.setups, &d.base_rms_per_setup)
    );
    let _ = writeln!(
        s,
        "Residual RMS per channel: {}.\n",
        per(d.quantity, &d.channels, &d.base_rms_per_channel)
    );
    let _ = writeln!(s, "## Structure left in the base residuals\n");
    let mut tests: Vec<_> = d.structure.iter().collect();
    tests.sort_by(|a, b| a.p_value.total_cmp(&b.p_value));
    let _ = writeln!(
        s,
        "| against | channel | test | share of residual | p (Bonferroni) |\n|---|---|---|---|---|"
    );
    for t in tests.iter().take(8) {
        let period = t.period.map(|p| format!(" ({p:.3})")).unwrap_or_default();
        let _ = writeln!(
            s,
            "| {} | {} | {}{period} | {:.0} % | {} |",
            t.variable,
            t.channel,
            t.test,
            100.0 * t.share_of_residual,
            p_text(t.p_value)
        );
    }
    if !d.not_separable.is_empty() {
        let _ = writeln!(s, "\n## Not separable with this data\n");
        for n in &d.not_separable {
            let _ = writeln!(
                s,
                "- {} ({}) is a combination of {}.{}",
                n.name,
                n.label,
                n.confounded_with.join(", "),
                n.separated_by
                    .as_ref()
                    .map(|h| format!(" Separate it with {h}."))
                    .unwrap_or_default()
            );
        }
    }
    let _ = writeln!(s, "\n## Search\n");
    for (k, step) in d.steps.iter().enumerate() {
        let ranked: Vec<String> = step
            .ranking
            .iter()
            .take(4)
            .map(|c| {
                format!(
                    "{} ({}{})",
                    c.name,
                    p_text(c.p_value),
                    c.held_out_rms
                        .map(|r| format!(", held out {}", level(d.quantity, r)))
                        .unwrap_or_default()
                )
            })
            .collect();
        let _ = writeln!(
            s,
            "{}. {} candidates tried; best: {}; {}.",
            k + 1,
            step.variants_tested,
            if ranked.is_empty() {
                "none".into()
            } else {
                ranked.join("; ")
            },
            step.added
                .as_ref()
                .map(|a| format!("added **{a}**"))
                .unwrap_or_else(|| "nothing significant: stop".into())
        );
    }
    s
}

fn per(q: Quantity, names: &[String], values: &[f64]) -> String {
    names
        .iter()
        .zip(values)
        .map(|(n, v)| format!("{n} {}", level(q, *v)))
        .collect::<Vec<_>>()
        .join(", ")
}

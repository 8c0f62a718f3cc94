//! The diagnosis as Markdown: what the model gets wrong, the named cause, the gain — readable by
//! an engineer in a minute.

use std::fmt::Write;

use crate::engine::{Diagnosis, Verdict};
use crate::term::{Quantity, significant_decimals};

/// An RMS, maximum or noise level of the observations as engineers quote it: µm for lengths,
/// arcsec for angles (a rotary axis' positioning deviations).
pub(crate) fn level(q: Quantity, v: f64) -> String {
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

/// `σ0 = …` against a stated noise; without one σ0 is the residuals' scatter in the data's unit
/// (unit weights), said as such.
fn scatter(d: &Diagnosis, sigma0: f64) -> String {
    if d.stated_noise.is_some() {
        format!("σ0 = {sigma0:.2}")
    } else {
        format!("the residual scatter is {}", level(d.quantity, sigma0))
    }
}

/// The compound effect or qualification ([`crate::Diagnosis::compound`]) the finding `name` is
/// part of.
fn caveat_of<'d>(d: &'d Diagnosis, name: &str) -> Option<&'d crate::Compound> {
    d.compound
        .iter()
        .find(|c| c.findings.iter().any(|f| f == name))
}

/// The readings the final model misses by far more than the rest, where they were taken, and
/// what the fit is without them.
fn outliers(s: &mut String, d: &Diagnosis) {
    const LISTED: usize = 12;
    if d.outliers.is_empty() {
        return;
    }
    let k = d.outliers.len();
    let without = d
        .without_outliers
        .map(|(sigma0, p)| {
            format!(
                " Without {}, {}{}.",
                if k == 1 { "it" } else { "them" },
                scatter(d, sigma0),
                p.map(|p| format!(" (χ² test {})", p_text(p)))
                    .unwrap_or_default()
            )
        })
        .unwrap_or_default();
    let _ = writeln!(
        s,
        "**{k} reading{} the model misses by far more than the rest** (|z| beyond what the largest of {} normal residuals reaches at the discovery level; z in units of the residuals' robust scatter). An isolated one points to a fault of the measurement (a beam break, a lost lock, a sensor glitch): check it and measure again or leave it out; several at one pose or time point to an effect the model lacks.{without}\n",
        if k == 1 { "" } else { "s" },
        d.observations,
    );
    let _ = writeln!(
        s,
        "| {} | channel | where | residual | z |\n|---|---|---|---|---|",
        d.setup_kind
    );
    for o in d.outliers.iter().take(LISTED) {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.1} |",
            o.setup, o.channel, o.place, o.text, o.z
        );
    }
    if k > LISTED {
        let _ = writeln!(
            s,
            "\n({} more in `outliers` of diagnosis.json.)",
            k - LISTED
        );
    }
    let _ = writeln!(s);
}

/// A p-value as text: "p = 0.012", "p = 3.1e-5", "p < 1e-12".
pub(crate) fn p_text(p: f64) -> String {
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
    if let Some(b) = &d.base_model {
        let _ = writeln!(
            s,
            "Base model ({}): {}; with the instrument's own parameters{}.\n",
            if b.stated {
                "as the dataset states it"
            } else {
                "none stated, the instrument's default"
            },
            b.description,
            match &b.instrument_terms[..] {
                [] => " (none)".to_string(),
                [one] => format!(" ({one})"),
                [first, rest @ ..] => format!(" ({}: {first}, …)", rest.len() + 1),
            }
        );
    }
    let _ = writeln!(s, "## Verdict\n");
    // Without a stated noise the residuals' size is not tested (σ0 is then their RMS in the
    // unit of the weights): only their structure is.
    let stated = d.stated_noise.is_some();
    let noise_fit = |q: &crate::engine::FitQuality| {
        if !stated {
            return format!(
                "residual RMS {}; no noise stated, so their size is not tested",
                level(d.quantity, q.rms)
            );
        }
        format!(
            "σ0 = {:.2}{}",
            q.sigma0,
            q.chi2_p_value
                .map(|p| format!(", χ² test {}", p_text(p)))
                .unwrap_or_default()
        )
    };
    // Within the tolerance the verdict allows, a χ² test that rejects is said in words: the
    // scatter is above the stated noise by more than chance, and what could hide in it is what
    // the detection limits state.
    let excess = |q: &crate::engine::FitQuality| match q.chi2_p_value {
        Some(p) if stated && p < d.alpha && q.sigma0 > 1.0 => format!(
            " The scatter is {:.2} × the stated noise: more than chance gives, within the factor {} to which a stated noise is usually known; {} may hide in it.",
            q.sigma0,
            crate::engine::STATED_NOISE_TOLERANCE,
            if d.detection_limits.is_empty() {
                "a cause too small for the search to find"
            } else {
                "a cause smaller than what these data could have shown (listed below)"
            }
        ),
        // Below it by more than chance: the noise stated is larger than the readings show, and
        // the uncertainties, which never take less than it, are wider than the data need.
        Some(p) if stated && 1.0 - p < d.alpha && q.sigma0 < 1.0 => format!(
            " The scatter is {:.2} × the stated noise: less than chance gives, so the readings repeat better than the noise stated; the uncertainties, which take the stated noise where the scatter is below it, are wider than these data need.",
            q.sigma0
        ),
        _ => String::new(),
    };
    match d.verdict {
        Verdict::NoDiscrepancy if stated => {
            let _ = writeln!(
                s,
                "**No significant discrepancy.** The base model explains the data to the noise: residual RMS {}, {}.{}\n",
                level(d.quantity, d.base.rms),
                noise_fit(&d.base),
                excess(&d.base)
            );
        }
        Verdict::NoDiscrepancy => {
            let _ = writeln!(
                s,
                "**No significant discrepancy.** The base model leaves no structure in the residuals ({}).\n",
                noise_fit(&d.base)
            );
        }
        Verdict::Explained => {
            let qualified = d
                .findings
                .iter()
                .filter(|f| caveat_of(d, &f.name).is_some() || !f.rivals.is_empty())
                .count();
            let _ = writeln!(
                s,
                "**The base model misses {} cause{}**, named below{}; with {} the residuals are {} ({}).{}\n",
                d.findings.len(),
                if d.findings.len() == 1 { "" } else { "s" },
                match (qualified, d.findings.len()) {
                    (0, _) => String::new(),
                    (1, 1) => " with a caveat on what these data can tell".to_string(),
                    (q, _) => format!(" ({q} with a caveat on what these data can tell)"),
                },
                if d.findings.len() == 1 { "it" } else { "them" },
                if stated {
                    "consistent with the noise"
                } else {
                    "left without structure"
                },
                noise_fit(&d.extended),
                excess(&d.extended)
            );
        }
        Verdict::Unexplained => {
            let _ = writeln!(
                s,
                "**The model does not explain the data{}.** {}\n",
                if d.findings.is_empty() {
                    ", and nothing in the library of physical effects does"
                } else {
                    " even with the causes named below"
                },
                unexplained(d)
            );
        }
    }
    for f in &d.findings {
        let est: Vec<String> = f
            .estimates
            .iter()
            .map(|e| format!("{} = {}", e.name, e.text))
            .collect();
        let hyper = f
            .hyper_parameter
            .as_ref()
            .map(|h| format!(" ({} {})", h.name, h.text))
            .unwrap_or_default();
        let _ = writeln!(
            s,
            "- **{}** — {}: {}{hyper}.",
            f.name,
            f.label,
            est.join(", ")
        );
        let _ = writeln!(s, "  {}.", f.meaning);
        let _ = writeln!(
            s,
            "  Entered at {}; in the complete model {}; cross-validated RMS inside the search {} → {}.",
            p_text(f.p_value),
            p_text(f.p_value_final),
            level(d.quantity, f.cv_rms_before),
            level(d.quantity, f.cv_rms_after),
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
        if let Some(g) = d
            .determined_together
            .iter()
            .find(|g| g.terms.contains(&f.name))
        {
            let others: Vec<&str> = g
                .terms
                .iter()
                .filter(|t| **t != f.name)
                .map(String::as_str)
                .collect();
            let _ = writeln!(
                s,
                "  Its size is determined only together with: {} (estimates correlated up to {:.4}; see below).",
                others.join(", "),
                g.largest_correlation
            );
        }
        if !f.rivals.is_empty() {
            let rivals: Vec<String> = f
                .rivals
                .iter()
                .map(|r| {
                    format!(
                        "{} (χ² {:.1} {} in its place)",
                        r.name,
                        r.chi2_excess.abs(),
                        if r.chi2_excess < 0.0 {
                            "lower"
                        } else {
                            "higher"
                        }
                    )
                })
                .collect();
            let _ = writeln!(
                s,
                "  These data hardly tell it from: {}; a difference in χ² below 6.6 (99 % for one degree of freedom) does not decide between causes.{}",
                rivals.join(", "),
                match (&f.separated_by, f.alternatives.is_empty()) {
                    (Some(h), true) => format!(" To separate them: {h}."),
                    _ => String::new(),
                }
            );
        }
        // A caveat on several findings follows the last of them.
        if let Some(c) = caveat_of(d, &f.name)
            && d.findings
                .iter()
                .rfind(|g| c.findings.contains(&g.name))
                .is_some_and(|g| g.name == f.name)
        {
            let _ = writeln!(s, "  Caveat: {}.", c.note);
        }
    }
    if !d.findings.is_empty() {
        let _ = writeln!(s);
    }
    outliers(&mut s, d);
    if let Some(h) = &d.held_out {
        let _ = writeln!(
            s,
            "**Gain on data the search did not see** ({} folds of contiguous blocks; for each, the base model and the whole search — choice of causes, periods, time constants — on the other folds predict it): held-out RMS {} → {}, held-out maximum {} → {}.\n",
            h.folds,
            level(d.quantity, h.base_rms),
            level(d.quantity, h.diagnosed_rms),
            level(d.quantity, h.base_max_abs),
            level(d.quantity, h.diagnosed_max_abs)
        );
        let differ = h.per_fold.iter().any(|names| {
            let mut a = names.clone();
            let mut b: Vec<String> = d.findings.iter().map(|f| f.name.clone()).collect();
            a.sort();
            b.sort();
            a != b
        });
        if differ {
            let folds: Vec<String> = h
                .per_fold
                .iter()
                .map(|n| {
                    if n.is_empty() {
                        "nothing".to_string()
                    } else {
                        n.join(", ")
                    }
                })
                .collect();
            let _ = writeln!(
                s,
                "Not every fold's search named the causes above; the folds' searches named: {}.\n",
                folds.join(" | ")
            );
        }
    }
    if let Some(why) = &d.incomplete {
        let _ = writeln!(s, "**The diagnosis is incomplete:** {why}.\n");
    }
    // (The compound effects' notes stand beside their findings.)
    for note in d
        .notes
        .iter()
        .filter(|n| !d.compound.iter().any(|c| &c.note == *n))
    {
        let _ = writeln!(s, "Note: {note}.\n");
    }
    if !d.base_completed.is_empty() {
        let _ = writeln!(
            s,
            "Component errors needed higher orders than the base model states, or than the polynomial a component error was found as (added to the base, before the search or once a cause that hid them or that they complete was in; not causes): {}.\n",
            d.base_completed.join(", ")
        );
    }
    if !d.exchanged.is_empty() {
        let swaps: Vec<String> = d
            .exchanged
            .iter()
            .map(|e| {
                if e.chi2_drop >= 0.0 {
                    format!(
                        "{} by {}, a rival that explains the data better (χ² lower by {:.1})",
                        e.replaced, e.by, e.chi2_drop
                    )
                } else {
                    format!(
                        "{} by {}, simpler, which the data do not tell from it (χ² higher by only {:.1})",
                        e.replaced, e.by, -e.chi2_drop
                    )
                }
            })
            .collect();
        let _ = writeln!(
            s,
            "Chosen during the search and replaced once the model was complete, each rival tried with the other causes fitted: {}.\n",
            swaps.join("; ")
        );
    }
    if !d.pruned.is_empty() {
        let _ = writeln!(
            s,
            "Added during the search and removed when re-tested in the complete model: {}.\n",
            d.pruned
                .iter()
                .map(|p| format!("{} ({})", p.name, p.reason.text()))
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
    if !d.passed_over.is_empty() {
        let items: Vec<String> = d
            .passed_over
            .iter()
            .map(|p| {
                format!(
                    "{} (at held-out {} positions the residuals' RMS {} by {:.1} %)",
                    p.name,
                    p.axis,
                    if p.ratio > 1.0 { "grew" } else { "fell only" },
                    100.0 * (p.ratio - 1.0).abs()
                )
            })
            .collect();
        let _ = writeln!(
            s,
            "Passed over: periodic errors at a free period that fitted the residuals but did not predict the readings at positions of their axis they were not fitted to (their period chosen on the other positions; a fall of {:.0} % needed) — structure of another form, not a pitch error these data show: {}.\n",
            100.0 * d.min_gain,
            items.join("; ")
        );
    }
    let _ = writeln!(s, "## Base model\n");
    let _ = writeln!(s, "| quality | fit | held out |\n|---|---|---|");
    let _ = writeln!(
        s,
        "| RMS | {} | {} |",
        level(d.quantity, d.base.rms),
        level(d.quantity, d.base.cv_rms)
    );
    let _ = writeln!(
        s,
        "| max | {} | {} |\n",
        level(d.quantity, d.base.max_abs),
        level(d.quantity, d.base.cv_max_abs)
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
        let period = t
            .period_text
            .as_ref()
            .map(|p| format!(" ({p})"))
            .unwrap_or_default();
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
    not_separable_section(
        &mut s,
        "Base parameters these data cannot separate",
        &d.base_not_separable,
        ": left out of the fit",
    );
    not_separable_section(&mut s, "Not separable with this data", &d.not_separable, "");
    determined_together_section(&mut s, d);
    detection_limits_section(&mut s, &d.detection_limits);
    let _ = writeln!(s, "\n## Search\n");
    for (k, step) in d.steps.iter().enumerate() {
        let ranked: Vec<String> = step
            .ranking
            .iter()
            .take(4)
            .map(|c| {
                format!(
                    "{}{} ({}{})",
                    c.name,
                    c.per_turn
                        .map(|k| format!(" at {k} per turn"))
                        .unwrap_or_default(),
                    p_text(c.p_value),
                    c.cv_rms
                        .map(|r| format!(", cross-validated {}", level(d.quantity, r)))
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
            match (&step.added, &d.incomplete) {
                (Some(a), _) => format!("added **{a}**"),
                (None, Some(_)) if k + 1 == d.steps.len() => "stop at a limit (see above)".into(),
                (None, _) => "nothing significant: stop".into(),
            }
        );
    }
    s
}

/// A section listing what the data cannot separate and with what it is confounded.
fn not_separable_section(
    s: &mut String,
    title: &str,
    items: &[crate::engine::NotSeparable],
    consequence: &str,
) {
    if items.is_empty() {
        return;
    }
    let _ = writeln!(s, "\n## {title}\n");
    for n in items {
        let _ = writeln!(
            s,
            "- {} ({}) {} {}{consequence}.{}",
            n.name,
            n.label,
            if n.rests_on_orders {
                "was found, but with the next order of every base error in the model it is nearly a combination of"
            } else {
                "is a combination of"
            },
            n.confounded_with.join(", "),
            n.separated_by
                .as_ref()
                .map(|h| format!(" Separate it with {h}."))
                .unwrap_or_default()
        );
    }
}

/// The groups of terms the data determine only together.
fn determined_together_section(s: &mut String, d: &Diagnosis) {
    let groups = &d.determined_together;
    if groups.is_empty() {
        return;
    }
    // Each term with its size in the final model (the first estimate; "…" where it has more).
    let sized = |name: &String| {
        let estimates = d
            .extended_parameters
            .iter()
            .find(|p| p.term == *name)
            .map(|p| &p.estimates[..])
            .unwrap_or_default();
        match estimates {
            [] => name.clone(),
            [e] => format!("{} = {}", e.name, e.text),
            [e, ..] => format!("{} = {} …", e.name, e.text),
        }
    };
    let _ = writeln!(
        s,
        "\n## Determined only together\n\nIn the final model the estimates of each group below (sizes in that model) are correlated beyond ±{} with another of the group: these data measure a combination of them, and the sizes of each are one split of it among many that fit nearly as well — a size no machine has is a sign of it. Other set-ups or positions, or a model without some of them, would tell them apart.\n",
        crate::engine::TOGETHER_CORRELATION
    );
    const SHOWN: usize = 12;
    for g in groups {
        let more = match g.terms.len().saturating_sub(SHOWN) {
            0 => String::new(),
            k => format!(" and {k} more"),
        };
        let _ = writeln!(
            s,
            "- {}{more} (|correlation| up to {:.4})",
            g.terms
                .iter()
                .take(SHOWN)
                .map(sized)
                .collect::<Vec<_>>()
                .join("; "),
            g.largest_correlation
        );
    }
}

/// A table of the sizes from which the causes not found would have been found.
fn detection_limits_section(s: &mut String, limits: &[crate::engine::DetectionLimit]) {
    if limits.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "\n## What these data could have shown\n\nThe causes of the library that were not found, with the size from which the search would find each {:.0} times in 100 (its tests, the model's residual scatter and what the model leaves of the cause's effect decide it; where the cause has a period or time constant, the range over those tested). A cause smaller than that may be present. The limits hold for the model as completed: where higher orders of the base entered because a cause was there, they hold part of it, and its limit is then too low.\n\n| cause | what | would be found from |\n|---|---|---|",
        100.0 * crate::engine::DETECTION_POWER
    );
    let mut rows: Vec<_> = limits.iter().collect();
    rows.sort_by(|a, b| a.name.cmp(&b.name));
    for l in rows {
        let (Some(small), Some(large)) = (l.smallest(), l.largest()) else {
            continue;
        };
        // The period or time constant in its unit.
        let value = |h: f64| {
            l.at_quantity.map_or(String::new(), |q| {
                let (g, u) = q.report_unit();
                let gap = if u == "°" { "" } else { " " };
                format!("{}{gap}{u}", significant(h * g))
            })
        };
        let what = if l.at_quantity == Some(Quantity::Duration) {
            "τ"
        } else {
            "period"
        };
        let size = |(h, v): (Option<f64>, f64)| {
            let (f, unit) = l.quantity.report_unit();
            let at = h.map_or(String::new(), |h| format!(" ({what} {})", value(h)));
            if v * f >= BEYOND_REACH {
                format!("beyond reach (≥ {BEYOND_REACH} {unit}){at}")
            } else {
                format!("{} {unit}{at}", significant(v * f))
            }
        };
        let mut text = if small == large {
            size(small)
        } else {
            format!("{} to {}", size(small), size(large))
        };
        let hidden: Vec<f64> = l
            .variants
            .iter()
            .filter(|v| v.size.is_none())
            .filter_map(|v| v.at)
            .collect();
        if !hidden.is_empty() {
            let lo = hidden.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = hidden.iter().copied().fold(0.0, f64::max);
            let span = if lo < hi {
                format!("{} to {}", value(lo), value(hi))
            } else {
                value(lo)
            };
            let held = if l.held_by.is_empty() {
                String::new()
            } else {
                format!(", where it is a combination of {}", l.held_by.join(", "))
            };
            text.push_str(&format!(
                "; not separable from the model at {} of the {} {what}s tested ({span}{held})",
                hidden.len(),
                l.variants.len()
            ));
        }
        let _ = writeln!(s, "| {} | {} | {text} |", l.name, l.label);
    }
}

/// A limit at or above this many of its reported unit (1 mm in µm, 1 mrad in µrad, 0.1 % in
/// ppm …) is no size an ordinary error of a machine tool has: the data cannot see the cause.
const BEYOND_REACH: f64 = 1000.0;

/// σ0 beyond which the misfit is the dataset's, not the machine's: residuals a hundred times
/// the stated noise (tens of µm and more for an instrument of a few tenths of a µm).
const GROSS_MISFIT: f64 = 100.0;

/// Three significant digits.
fn significant(v: f64) -> String {
    let digits = (2 - v.abs().max(1e-300).log10().floor() as i32).clamp(0, 6) as usize;
    format!("{v:.digits$}")
}

/// Where the unexplained structure is, in words.
fn unexplained(d: &Diagnosis) -> String {
    let mut parts = Vec::new();
    let mut tests: Vec<_> = d.remaining_structure.iter().collect();
    tests.sort_by(|a, b| a.p_value.total_cmp(&b.p_value));
    for t in tests.iter().take(4) {
        let period = t
            .period_text
            .as_ref()
            .map(|p| format!(", period {p}"))
            .unwrap_or_default();
        parts.push(format!(
            "the {} residuals still depend on {} ({}{period}; {:.0} % of the residual, {})",
            t.channel,
            t.variable,
            t.test,
            100.0 * t.share_of_residual,
            p_text(t.p_value)
        ));
    }
    let mut text = if parts.is_empty() {
        String::new()
    } else {
        format!("Unexplained structure: {}. ", parts.join("; "))
    };
    if d.extended.chi2_p_value.is_some()
        && d.extended.sigma0 > crate::engine::STATED_NOISE_TOLERANCE
    {
        text.push_str(&format!(
            "The residuals are {} times the stated noise (σ0, χ² test {}).",
            significant(d.extended.sigma0),
            d.extended.chi2_p_value.map(p_text).unwrap_or_default()
        ));
        if let (Some(stated), true) = (
            d.stated_noise,
            parts.is_empty() && d.outliers.is_empty() && d.extended.sigma0 <= GROSS_MISFIT,
        ) {
            // A scatter above the stated noise with no pattern in it: most often a noise stated
            // too small (an instrument's resolution given for its repeatability).
            text.push_str(&format!(
                " The structure tests (trends and periods along each variable, direction, set-ups) find no pattern in them: a scatter without structure is the measurement's own, about {} where {} is stated. Check the stated noise (the instrument's repeatability in these conditions, not its resolution); many causes below the detection limits at once would leave such a scatter too.",
                level(d.quantity, d.extended.sigma0 * stated),
                level(d.quantity, stated)
            ));
        }
        if d.extended.sigma0 > GROSS_MISFIT {
            text.push_str(" Residuals this large are no machine error of a few µm or µrad: check the dataset itself — the units of each column, the axes' signs and directions in the machine file, the stated noise, the offsets of targets or reflectors (a table that leaves them out, or states them as zeros, for readings taken with them).");
        }
    }
    if let Some((sigma0, _)) = d.without_outliers {
        text.push_str(&format!(
            " Without the {} listed below, {}.",
            if d.outliers.len() == 1 {
                "reading".to_string()
            } else {
                format!("{} readings", d.outliers.len())
            },
            scatter(d, sigma0)
        ));
    }
    text.trim_end().to_string()
}

fn per(q: Quantity, names: &[String], values: &[f64]) -> String {
    names
        .iter()
        .zip(values)
        .map(|(n, v)| format!("{n} {}", level(q, *v)))
        .collect::<Vec<_>>()
        .join(", ")
}

//! Basis functions of covariates: Legendre polynomials over the observed range, sine/cosine
//! pairs of a period, exponential approach in time, and the grids of periods and time
//! constants the diagnosis scans.

use mte_linalg::{DMat, DVec};

/// Range of the values (min, max).
pub(crate) fn range(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        })
}

/// Polynomials of the values mapped onto [−1, 1] over their observed range, one column per
/// degree in `degrees` (an empty column set when the values do not vary): Legendre's P_d made
/// orthogonal to every lower degree over the distinct values, each counted once (Gram–Schmidt,
/// P_d less its projections), so that a term's lower degrees hold what they would alone. A
/// component error's linear part is then the slope of the least-squares line through what the
/// measured positions show — the reference line of ISO 230-1, whose slope is a squareness or a
/// scale — and its constant their mean, however few the positions: Legendre's polynomials are
/// orthogonal over the interval, not at 4 or 5 positions, where P_3 holds much of a line. Dense
/// positions give P_d itself. A degree the distinct values cannot carry apart from the lower
/// ones (d ≥ their number) is a column of zeros.
pub(crate) fn legendre_columns(values: &[f64], degrees: std::ops::RangeInclusive<usize>) -> DMat {
    let (lo, hi) = range(values);
    let n = values.len();
    let degrees: Vec<usize> = degrees.collect();
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return DMat::zeros(n, 0);
    }
    let max_degree = degrees.iter().copied().max().unwrap_or(0);
    let unit = |v: f64| 2.0 * (v - lo) / (hi - lo) - 1.0;
    let coefficients = orthogonalising(
        &distinct_sorted(values)
            .into_iter()
            .map(unit)
            .collect::<Vec<_>>(),
        max_degree,
    );
    // The recursion once per value (every degree of a row from one pass).
    let mut m = DMat::zeros(n, degrees.len());
    let mut p = Vec::with_capacity(max_degree + 2);
    for (i, v) in values.iter().enumerate() {
        legendre_into(max_degree, unit(*v), &mut p);
        for (j, &d) in degrees.iter().enumerate() {
            m[(i, j)] = coefficients[d].iter().zip(&p).map(|(c, p)| c * p).sum();
        }
    }
    m
}

/// The coefficients over P_0 … P_max of the polynomials orthogonal at the points `u` (modified
/// Gram–Schmidt in the order of the degrees, each P_d less its projections on the lower ones):
/// row d holds Q_d = Σ_j c_dj P_j, with c_dd = 1, or zeros where P_d is a combination of the
/// lower degrees at these points.
fn orthogonalising(u: &[f64], max_degree: usize) -> Vec<Vec<f64>> {
    // P_d at the points, one column per degree.
    let mut at = DMat::zeros(u.len(), max_degree + 1);
    let mut p = Vec::with_capacity(max_degree + 2);
    for (i, &u) in u.iter().enumerate() {
        legendre_into(max_degree, u, &mut p);
        at.row_mut(i).iter_mut().zip(&p).for_each(|(a, p)| *a = *p);
    }
    let mut q: Vec<Vec<f64>> = Vec::with_capacity(max_degree + 1);
    let mut coefficients: Vec<Vec<f64>> = Vec::with_capacity(max_degree + 1);
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
    for d in 0..=max_degree {
        let mut v: Vec<f64> = at.column(d).iter().copied().collect();
        let mut c = vec![0.0; max_degree + 1];
        c[d] = 1.0;
        let before = dot(&v, &v);
        for (qj, cj) in q.iter().zip(&coefficients) {
            let norm = dot(qj, qj);
            if norm == 0.0 {
                continue;
            }
            let r = dot(&v, qj) / norm;
            v.iter_mut().zip(qj).for_each(|(v, q)| *v -= r * q);
            c.iter_mut().zip(cj).for_each(|(c, cj)| *c -= r * cj);
        }
        // What is left of P_d at these points is rounding: a combination of the lower degrees.
        if dot(&v, &v) <= 1e-20 * before {
            v.iter_mut().for_each(|v| *v = 0.0);
            c.iter_mut().for_each(|c| *c = 0.0);
        }
        q.push(v);
        coefficients.push(c);
    }
    coefficients
}

/// P_0 … P_n at u by Bonnet's recursion, into `p` (cleared first).
fn legendre_into(n: usize, u: f64, p: &mut Vec<f64>) {
    p.clear();
    p.extend([1.0, u]);
    for k in 1..n {
        let k = k as f64;
        let next = ((2.0 * k + 1.0) * u * p[k as usize] - k * p[k as usize - 1]) / (k + 1.0);
        p.push(next);
    }
    p.truncate(n + 1);
}

/// `sin(2π v / period)` and `cos(2π v / period)`.
pub(crate) fn sin_cos_columns(values: &[f64], period: f64) -> DMat {
    let n = values.len();
    let mut m = DMat::zeros(n, 2);
    for (i, &v) in values.iter().enumerate() {
        let (s, c) = sin_cos_turns(v / period);
        m[(i, 0)] = s;
        m[(i, 1)] = c;
    }
    m
}

/// `sin(2π x)` and `cos(2π x)`, reduced to an eighth of a turn in `x` first: exact
/// reduction (the subtraction of a nearby multiple of ¼ is exact), then the trigonometric
/// functions on |phase| ≤ π/4, their fast path — the scans evaluate millions of them.
fn sin_cos_turns(x: f64) -> (f64, f64) {
    let quarters = (4.0 * x).round();
    let phase = std::f64::consts::TAU * (x - 0.25 * quarters);
    let (s, c) = (phase.sin(), phase.cos());
    // (An integer remainder: f64's `rem_euclid` is a slow software fmod.)
    match (quarters as i64).rem_euclid(4) {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// Fewest distinct positions along an axis for a period scan: a sine has three parameters
/// (amplitude, phase, period) on top of the polynomial the base already carries there.
pub(crate) const LEAST_POSITIONS: usize = 6;

/// Highest harmonic of a turn scanned on a rotary axis: 2°, a worm wheel's tooth period.
const MAX_HARMONIC: usize = 180;

/// The periods the sampling of an axis lets the diagnosis look for ([`periods_to_scan`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Reach {
    /// Distinct positions.
    pub positions: usize,
    /// Shortest and longest period scanned (mm, or rad for a rotary axis); `None` when the
    /// sampling allows none (fewer than [`LEAST_POSITIONS`] positions, or a linear axis whose
    /// shortest resolvable period exceeds half its travel).
    pub periods: Option<(f64, f64)>,
    /// The alias period of the positions when it, not the resolution floor, sets the shortest
    /// period: the positions repeat (nearly) on this step.
    pub alias: Option<f64>,
}

/// Periods to scan along an axis.
///
/// For a rotary axis, the harmonics of a turn (an error that repeats every turn has no other
/// periods): 1 … 8, and up to the 180th (2°, a worm wheel's tooth period) as far as the
/// sampling resolves them without aliasing. For a linear axis, uniform in frequency (twice the
/// Fourier resolution 1/travel) from travel ÷ 2 (at least two periods in the travel: a longer wave
/// is a smooth component error, which polynomials and the base's completion describe) down to
/// the shortest period the sampling
/// can tell from its aliases: 2.5 × the alias period of the target positions (see
/// [`alias_period`]), and never below travel ÷ 1000 or 1 mm. ISO 230-2 asks for irregular target
/// spacing precisely so that a ball-screw pitch shorter than the mean step is still seen; on a
/// regular grid of step d the alias period is d and the scan stops at 2.5 d, as Nyquist demands.
pub(crate) fn periods_to_scan(values: &[f64], rotary: bool) -> Vec<f64> {
    let Some((lo, hi)) = periodic_reach(values, rotary).periods else {
        return Vec::new();
    };
    if rotary {
        let highest = (std::f64::consts::TAU / lo).round() as usize;
        return (1..=highest)
            .rev()
            .map(|k| std::f64::consts::TAU / k as f64)
            .collect();
    }
    let travel = 2.0 * hi;
    let df = 0.5 / travel;
    let (f_lo, f_hi) = (1.0 / hi, 1.0 / lo);
    let count = ((f_hi - f_lo) / df).ceil() as usize + 1;
    let mut periods: Vec<f64> = (0..count)
        .map(|k| 1.0 / (f_hi - k as f64 * (f_hi - f_lo) / (count - 1).max(1) as f64))
        .collect();
    periods.sort_by(f64::total_cmp);
    periods
}

/// The range of periods [`periods_to_scan`] covers along an axis sampled at `values`, and what
/// limits it.
pub(crate) fn periodic_reach(values: &[f64], rotary: bool) -> Reach {
    let mut positions = distinct_sorted(values);
    let count = positions.len();
    let none = Reach {
        positions: count,
        periods: None,
        alias: None,
    };
    if count < LEAST_POSITIONS {
        return none;
    }
    // A dense record (a continuous log) is judged by at most 20 000 of its positions, evenly by
    // rank, ends kept: their spacing is still far below the shortest period scanned, and the
    // alias search stays cheap.
    const MOST_POSITIONS: usize = 20_000;
    if count > MOST_POSITIONS {
        let last = positions[count - 1];
        let step = count.div_ceil(MOST_POSITIONS);
        positions = positions.into_iter().step_by(step).collect();
        if positions.last() != Some(&last) {
            positions.push(last);
        }
    }
    if rotary {
        const TURN: f64 = std::f64::consts::TAU;
        let alias = alias_period(&positions, TURN / MAX_HARMONIC as f64);
        let resolvable = alias.map_or(MAX_HARMONIC, |alias| {
            (TURN / (2.5 * alias)).floor() as usize
        });
        let highest = resolvable.clamp(8, MAX_HARMONIC);
        return Reach {
            periods: Some((TURN / highest as f64, TURN)),
            alias: alias.filter(|_| highest < MAX_HARMONIC),
            ..none
        };
    }
    let travel = positions[positions.len() - 1] - positions[0];
    let shortest_resolvable = (travel / 1000.0).max(1.0);
    let alias = alias_period(&positions, shortest_resolvable)
        .filter(|alias| 2.5 * alias > shortest_resolvable);
    let lo = alias.map_or(shortest_resolvable, |alias| 2.5 * alias);
    let hi = travel / 2.0;
    Reach {
        periods: (hi.partial_cmp(&lo) == Some(std::cmp::Ordering::Greater)).then_some((lo, hi)),
        alias,
        ..none
    }
}

/// The longest period, not shorter than `shortest`, at which the sampling positions are nearly
/// indistinguishable from a constant: the first peak of the spectral window
/// W(f) = |mean_k exp(2πi f x_k)|² above 0.8 beyond the main lobe. A sine of frequency f₀ and
/// one of f₀ ± 1/alias then fit the data almost equally well, so periods below twice the alias
/// cannot be told apart. `None` when the positions are irregular enough to alias nowhere above
/// `shortest` (the usual ISO 230-2 design with irregular steps).
pub(crate) fn alias_period(positions: &[f64], shortest: f64) -> Option<f64> {
    const ALIAS_POWER: f64 = 0.8;
    let (lo, hi) = range(positions);
    let travel = hi - lo;
    if travel.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    // Steps of an eighth of the Fourier resolution find the alias peak (width ~1/travel).
    let df = 0.125 / travel;
    let n = positions.len() as f64;
    // Each position's phasor exp(2πi f x) is advanced by a fixed rotation per frequency step
    // (renormalised now and then), so the scan costs a few multiplications per position.
    let f0 = 2.0 / travel;
    let turn = |f: f64, x: f64| {
        let phase = std::f64::consts::TAU * f * (x - lo);
        (phase.cos(), phase.sin())
    };
    let mut phasors: Vec<(f64, f64)> = positions.iter().map(|&x| turn(f0, x)).collect();
    let steps: Vec<(f64, f64)> = positions.iter().map(|&x| turn(df, x)).collect();
    let count = ((1.0 / shortest - f0) / df).floor().max(0.0) as usize;
    for k in 0..=count {
        let (c, s) = phasors
            .iter()
            .fold((0.0, 0.0), |(c, s), &(re, im)| (c + re, s + im));
        if (c * c + s * s) / (n * n) >= ALIAS_POWER {
            return Some(1.0 / (f0 + k as f64 * df));
        }
        let renormalise = k % 64 == 63;
        for (z, &(sr, si)) in phasors.iter_mut().zip(&steps) {
            let (re, im) = (z.0 * sr - z.1 * si, z.0 * si + z.1 * sr);
            let norm = if renormalise { re.hypot(im) } else { 1.0 };
            *z = (re / norm, im / norm);
        }
    }
    None
}

/// The distinct values of `values` (closer than 1e-9 count as one), sorted.
pub(crate) fn distinct_sorted(values: &[f64]) -> Vec<f64> {
    let mut sorted: Vec<f64> = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    sorted
}

/// Time constants to scan for a first-order thermal drift: log-spaced from 1/20 of the time span
/// of the data (but never below `floor`, set by the interval between repeated visits of a pose:
/// `candidate::shortest_time_constant`) to twice the span.
pub(crate) fn time_constants_to_scan(times: &[f64], floor: f64) -> Vec<f64> {
    let (lo, hi) = range(times);
    let span = hi - lo;
    let shortest = (span / 20.0).max(floor);
    let longest = 2.0 * span;
    if longest.partial_cmp(&shortest) != Some(std::cmp::Ordering::Greater) {
        return Vec::new();
    }
    let count = 12;
    (0..count)
        .map(|k| shortest * (longest / shortest).powf(k as f64 / (count - 1) as f64))
        .collect()
}

/// SplitMix64's output function of `i`: a well-mixed deterministic pseudo-random integer.
pub(crate) fn splitmix64(i: u64) -> u64 {
    let mut z = i.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A minimiser of `f` on `[a, b]` to within `tolerance`: Brent's bounded method (parabolic
/// steps where the function is smooth, golden-section steps where not; scipy's `fminbound`),
/// about a third of the evaluations golden-section search needs for the same precision.
/// Returns the best point evaluated and its value. At most 200 evaluations.
pub(crate) fn bounded_minimum(
    a: f64,
    b: f64,
    tolerance: f64,
    f: impl Fn(f64) -> f64,
) -> (f64, f64) {
    const MAX_EVALUATIONS: usize = 200;
    let sqrt_eps = f64::EPSILON.sqrt();
    let golden = 0.5 * (3.0 - 5f64.sqrt());
    let (mut a, mut b) = (a.min(b), a.max(b));
    // x: the best point, w the second best, v the previous w.
    let mut x = a + golden * (b - a);
    let mut fx = f(x);
    let (mut w, mut fw, mut v, mut fv) = (x, fx, x, fx);
    let (mut step, mut previous) = (0.0f64, 0.0f64);
    for _ in 1..MAX_EVALUATIONS {
        let middle = 0.5 * (a + b);
        let tol1 = sqrt_eps * x.abs() + tolerance / 3.0;
        let tol2 = 2.0 * tol1;
        if (x - middle).abs() <= tol2 - 0.5 * (b - a) {
            break;
        }
        let mut parabolic = false;
        if previous.abs() > tol1 {
            let r = (x - w) * (fx - fv);
            let q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            let mut q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            }
            q = q.abs();
            let before = previous;
            previous = step;
            if p.abs() < (0.5 * q * before).abs() && p > q * (a - x) && p < q * (b - x) {
                step = p / q;
                parabolic = true;
                let u = x + step;
                if u - a < tol2 || b - u < tol2 {
                    step = if middle >= x { tol1 } else { -tol1 };
                }
            }
        }
        if !parabolic {
            previous = if x >= middle { a - x } else { b - x };
            step = golden * previous;
        }
        let u = x + if step >= 0.0 {
            step.max(tol1)
        } else {
            step.min(-tol1)
        };
        let fu = f(u);
        if fu <= fx {
            if u >= x {
                a = x;
            } else {
                b = x;
            }
            (v, fv, w, fw, x, fx) = (w, fw, x, fx, u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv, w, fw) = (w, fw, u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    (x, fx)
}

/// Columns that are functions of one variable which each observation sees at a few poses, each
/// with its own sensitivity (an R-test reading sees a positioning error at its pose and, with
/// the opposite sign, at its setup's centring): `S B`, with `B` the functions at the variable's
/// `m` distinct values and `S` an `n × m` matrix of a few entries per row. A scan over many
/// periods of such functions ([`crate::Candidate::spread`]) costs the distinct values, not the
/// observations, in the diagnosis' products: runs and program cycles repeat their positions.
#[derive(Debug, Clone)]
pub struct Spread {
    /// The distinct values, increasing.
    values: Vec<f64>,
    rows: usize,
    /// Pose after pose (`poses × rows`): each row's value (index into `values`) and sensitivity.
    group: Vec<usize>,
    weight: Vec<f64>,
}

impl Spread {
    /// The spread of `poses`: for each, the variable's value and the sensitivity of every
    /// observation there.
    ///
    /// # Panics
    /// If the slices are not all of one length.
    pub fn new(poses: &[(&[f64], &[f64])]) -> Spread {
        let rows = poses.first().map_or(0, |p| p.0.len());
        assert!(
            poses.iter().all(|p| p.0.len() == rows && p.1.len() == rows),
            "one value and one sensitivity per observation at every pose"
        );
        let all: Vec<f64> = poses.iter().flat_map(|p| p.0.iter().copied()).collect();
        // Each row's value's rank among the distinct values.
        let mut order: Vec<usize> = (0..all.len()).collect();
        order.sort_by(|&a, &b| all[a].total_cmp(&all[b]));
        let mut values: Vec<f64> = Vec::new();
        let mut group = vec![0; all.len()];
        for i in order {
            if values.last() != Some(&all[i]) {
                values.push(all[i]);
            }
            group[i] = values.len() - 1;
        }
        Spread {
            values,
            rows,
            group,
            weight: poses.iter().flat_map(|p| p.1.iter().copied()).collect(),
        }
    }

    /// The number of observations.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// The variable's distinct values, increasing: where a basis is evaluated.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// `S b`: the observations' columns of the functions whose values at
    /// [`Spread::values`] are `b`'s columns.
    pub fn expand(&self, b: &DMat) -> DMat {
        assert_eq!(b.nrows(), self.values.len(), "one row per distinct value");
        let n = self.rows;
        let mut out = DMat::zeros(n, b.ncols());
        for (bj, mut oj) in b.column_iter().zip(out.column_iter_mut()) {
            for (group, weight) in self
                .group
                .chunks_exact(n.max(1))
                .zip(self.weight.chunks_exact(n.max(1)))
            {
                for (o, (&g, &w)) in oj.iter_mut().zip(group.iter().zip(weight)) {
                    *o += w * bj[g];
                }
            }
        }
        out
    }

    /// Whether every column of `spread.expand(b)` is zero (below 1e-15 in every row, as
    /// [`crate::Term::is_invisible`]): functions the observations do not see. Without forming
    /// the columns.
    pub fn sees_nothing(&self, b: &DMat) -> bool {
        assert_eq!(b.nrows(), self.values.len(), "one row per distinct value");
        let (n, poses) = (self.rows, self.poses());
        b.column_iter().all(|bj| {
            (0..n).all(|i| {
                let mut v = 0.0;
                for k in 0..poses {
                    v += self.weight[k * n + i] * bj[self.group[k * n + i]];
                }
                v.abs() < 1e-15
            })
        })
    }

    /// The spread on the observations `rows` only (the same distinct values).
    pub fn select_rows(&self, rows: &[usize]) -> Spread {
        let n = self.rows;
        let at: Vec<usize> = (0..self.poses())
            .flat_map(|k| rows.iter().map(move |&i| k * n + i))
            .collect();
        Spread {
            values: self.values.clone(),
            rows: rows.len(),
            group: at.iter().map(|&a| self.group[a]).collect(),
            weight: at.iter().map(|&a| self.weight[a]).collect(),
        }
    }

    /// How many poses each observation sees the variable at.
    fn poses(&self) -> usize {
        self.group.len().checked_div(self.rows).unwrap_or(0)
    }

    /// `Sᵀ diag(d) x` over the observations `rows` (none: all), `m ×` x's columns: the
    /// products `Cᵀ diag(d) x` of the columns `C = S B` of any functions `B` of the variable
    /// are `Bᵀ` times it.
    pub(crate) fn weighted_sums(&self, x: &DMat, d: &DVec, rows: Option<&[usize]>) -> DMat {
        let n = self.rows;
        let mut z = DMat::zeros(self.values.len(), x.ncols());
        // Each row's (value, weight) at every pose, once for all columns of x.
        let mut entries: Vec<(usize, usize, f64)> = Vec::new();
        let mut push = |i: usize| {
            for k in 0..self.poses() {
                let c = self.weight[k * n + i] * d[i];
                if c != 0.0 {
                    entries.push((i, self.group[k * n + i], c));
                }
            }
        };
        match rows {
            Some(rows) => rows.iter().for_each(|&i| push(i)),
            None => (0..n).for_each(&mut push),
        }
        for (xj, mut zj) in x.column_iter().zip(z.column_iter_mut()) {
            for &(i, g, c) in &entries {
                zj[g] += c * xj[i];
            }
        }
        z
    }

    /// `Sᵀ diag(w2) S` (`m × m`, a few entries per observation) as its nonzero entries on and
    /// above the diagonal: the Gram `Cᵀ diag(w2) C` of the columns of any functions `B` is
    /// `Bᵀ` it `B` ([`Spread::quadratic`]).
    pub(crate) fn gram(&self, w2: &DVec) -> Vec<(usize, usize, f64)> {
        let n = self.rows;
        let mut entries: Vec<(usize, usize, f64)> = Vec::new();
        for i in 0..n {
            for k in 0..self.poses() {
                for l in k..self.poses() {
                    let (a, b) = (self.group[k * n + i], self.group[l * n + i]);
                    let c = self.weight[k * n + i] * self.weight[l * n + i] * w2[i];
                    // Two poses at one value are one entry of twice the cross weight.
                    let c = if k == l || a != b { c } else { 2.0 * c };
                    entries.push((a.min(b), a.max(b), c));
                }
            }
        }
        entries.sort_by_key(|&(a, b, _)| (a, b));
        let mut merged: Vec<(usize, usize, f64)> = Vec::new();
        for (a, b, c) in entries {
            match merged.last_mut() {
                Some(last) if (last.0, last.1) == (a, b) => last.2 += c,
                _ => merged.push((a, b, c)),
            }
        }
        merged
    }

    /// `Bᵀ M B` of the functions `b` at the spread's values and the entries `m` of a symmetric
    /// matrix on and above its diagonal ([`Spread::gram`]).
    pub(crate) fn quadratic(m: &[(usize, usize, f64)], b: &DMat) -> DMat {
        let k = b.ncols();
        let mut out = DMat::zeros(k, k);
        for &(g, h, c) in m {
            for i in 0..k {
                for j in 0..k {
                    let v = if g == h {
                        c * b[(g, i)] * b[(g, j)]
                    } else {
                        c * (b[(g, i)] * b[(h, j)] + b[(h, i)] * b[(g, j)])
                    };
                    out[(i, j)] += v;
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spread_gives_the_columns_and_products_of_its_functions_at_every_pose() {
        // Six readings at three positions, each seen at its pose and at a reference pose
        // (as an R-test reading sees a positioning error): column i = a_i g(x_i) + r_i g(x_ref,i);
        // the third reading is at its reference position.
        let x = [10.0, 20.0, 10.0, 30.0, 20.0, 10.0];
        let x_ref = [0.0, 0.0, 10.0, 25.0, 25.0, 25.0];
        let a = [1.0, -0.5, 0.3, 2.0, 0.7, -1.1];
        let r = [-1.0, 0.5, -0.3, -0.4, -0.7, 1.1];
        let spread = Spread::new(&[(&x, &a), (&x_ref, &r)]);
        assert_eq!(spread.values(), &[0.0, 10.0, 20.0, 25.0, 30.0]);
        let g = |v: f64| [v.sin(), (v * v / 100.0).cos()];
        let b = DMat::from_fn(5, 2, |k, j| g(spread.values()[k])[j]);
        let direct = DMat::from_fn(6, 2, |i, j| a[i] * g(x[i])[j] + r[i] * g(x_ref[i])[j]);
        let columns = spread.expand(&b);
        assert!((&columns - &direct).amax() < 1e-15);
        // Seen: as the columns say (a function of the positions only at 25, a reference
        // position whose two readings' weights there differ, is seen too).
        assert!(!spread.sees_nothing(&b));
        assert!(spread.sees_nothing(&DMat::zeros(5, 2)));
        let at_25 = DMat::from_fn(5, 1, |k, _| if k == 3 { 1e-3 } else { 0.0 });
        assert!(!spread.sees_nothing(&at_25));
        assert!(spread.expand(&at_25).amax() >= 1e-15);
        // Products with a design under weights, over some rows: Bᵀ (Sᵀ W² X) = Cᵀ W² X.
        let design = DMat::from_fn(6, 3, |i, j| ((i * 3 + j) as f64).cos());
        let w2 = DVec::from_fn(6, |i, _| 1.0 + i as f64);
        let rows = [1, 3, 4];
        let sums = spread.weighted_sums(&design, &w2, Some(&rows));
        let want = DMat::from_fn(2, 3, |j, k| {
            rows.iter()
                .map(|&i| direct[(i, j)] * w2[i] * design[(i, k)])
                .sum()
        });
        assert!((b.transpose() * sums - want).amax() < 1e-13);
        let gram = Spread::quadratic(&spread.gram(&w2), &b);
        let want = direct.transpose() * DMat::from_diagonal(&w2) * &direct;
        assert!((gram - want).amax() < 1e-12);
        // On rows only: the same functions, the rows' columns.
        let on_rows = spread.select_rows(&rows);
        assert!((on_rows.expand(&b) - direct.select_rows(&rows)).amax() < 1e-15);
    }

    #[test]
    fn bounded_minimum_finds_known_minima_to_tolerance_in_few_evaluations() {
        use std::cell::Cell;
        // (function, bracket, true minimiser): a parabola, a smooth non-quadratic minimum
        // (x·e^(−x) reversed: minimum of −x e^(−x) at 1), a minimum at the bracket's edge.
        type Case<'a> = (&'a dyn Fn(f64) -> f64, f64, f64, f64);
        let cases: [Case; 3] = [
            (&|x: f64| (x - 1.234).powi(2), 0.0, 3.0, 1.234),
            (&|x: f64| -x * (-x).exp(), 0.2, 4.0, 1.0),
            (&|x: f64| x, 2.0, 5.0, 2.0),
        ];
        for (f, a, b, truth) in cases {
            let calls = Cell::new(0usize);
            let tolerance = 1e-5 * (b - a);
            let (x, fx) = bounded_minimum(a, b, tolerance, |x| {
                calls.set(calls.get() + 1);
                f(x)
            });
            assert!((x - truth).abs() < 2.0 * tolerance, "{x} against {truth}");
            assert_eq!(fx, f(x));
            // Golden-section search needs 25 evaluations for 1e-5 of the bracket.
            assert!(calls.get() <= 25, "{} evaluations", calls.get());
        }
    }

    #[test]
    fn sin_cos_of_turns_matches_the_library_functions() {
        for k in -2000..2000 {
            // Positions in mm over periods of a few mm and of a turn: phases up to ~10⁴ rad.
            let x = k as f64 * 0.3711 / 0.987;
            let (s, c) = sin_cos_turns(x);
            let phase = std::f64::consts::TAU * x;
            // The library's own reduction of the rounded phase is off by up to ulp(phase).
            let tol = 4.0 * f64::EPSILON * phase.abs().max(1.0);
            assert!((s - phase.sin()).abs() < tol, "sin at {x}");
            assert!((c - phase.cos()).abs() < tol, "cos at {x}");
        }
    }

    #[test]
    fn legendre_matches_closed_forms() {
        for &u in &[-1.0, -0.3, 0.0, 0.7, 1.0] {
            let mut p = Vec::new();
            legendre_into(3, u, &mut p);
            assert!((p[2] - 0.5 * (3.0 * u * u - 1.0)).abs() < 1e-15);
            assert!((p[3] - 0.5 * (5.0 * u * u * u - 3.0 * u)).abs() < 1e-15);
        }
    }

    /// At a few positions (each measured several times) the polynomials are orthogonal over the
    /// distinct positions, so a cubic fit's linear coefficient is the slope of the least-squares
    /// line through them (ISO 230-1's reference line); a degree the positions cannot carry is a
    /// column of zeros; at dense positions they are Legendre's.
    #[test]
    fn polynomials_are_orthogonal_at_the_positions_and_legendres_when_dense() {
        let positions = [-250.0, -120.0, 0.0, 130.0, 250.0];
        let values: Vec<f64> = positions.iter().flat_map(|&x| [x; 3]).collect();
        let q = legendre_columns(&values, 0..=5);
        let at = |d: usize| -> Vec<f64> { (0..5).map(|k| q[(3 * k, d)]).collect() };
        for i in 0..5 {
            for j in 0..i {
                let dot: f64 = at(i).iter().zip(at(j)).map(|(a, b)| a * b).sum();
                assert!(dot.abs() < 1e-12, "Q{i}·Q{j} = {dot}");
            }
        }
        assert!(at(4).iter().any(|v| v.abs() > 1e-3));
        assert!(at(5).iter().all(|v| *v == 0.0), "{:?}", at(5));
        // A wavy function's cubic fit at the positions: its linear coefficient, on the unit
        // coordinate, is the least-squares slope through the five values.
        let f = |x: f64| 3.0 + 2e-3 * x + (x / 60.0).sin();
        let x = DMat::from_fn(5, 4, |k, d| at(d)[k]);
        let y = DVec::from_fn(5, |k, _| f(positions[k]));
        let beta = x.clone().svd(true, true).solve(&y, 1e-12).unwrap();
        let mean = positions.iter().sum::<f64>() / 5.0;
        let slope = positions.iter().map(|&p| (p - mean) * f(p)).sum::<f64>()
            / positions.iter().map(|&p| (p - mean).powi(2)).sum::<f64>();
        assert!(
            (beta[1] / 250.0 - slope).abs() < 1e-12,
            "{} vs {slope}",
            beta[1] / 250.0
        );
        let dense: Vec<f64> = (0..=4000).map(|i| -1.0 + i as f64 / 2000.0).collect();
        let q = legendre_columns(&dense, 3..=3);
        for (i, &u) in dense.iter().enumerate().step_by(400) {
            let p3 = 0.5 * (5.0 * u * u * u - 3.0 * u);
            assert!(
                (q[(i, 0)] - p3).abs() < 2e-3,
                "{} vs {p3} at {u}",
                q[(i, 0)]
            );
        }
    }

    #[test]
    fn period_grid_respects_sampling() {
        // Regular grid of step 10 mm: aliases at 10 mm, so the scan stops at 25 mm (Nyquist).
        let x: Vec<f64> = (0..=70).map(|i| i as f64 * 10.0).collect();
        assert!((alias_period(&x, 1.0).unwrap() - 10.0).abs() < 0.05);
        let p = periods_to_scan(&x, false);
        assert!((p[0] - 2.5 * alias_period(&x, 1.0).unwrap()).abs() < 1e-9);
        assert!((p[p.len() - 1] - 700.0 / 2.0).abs() < 1e-9);
        assert!(p.windows(2).all(|w| w[1] > w[0]));
    }

    #[test]
    fn reach_names_what_limits_the_scan() {
        // Six positions on a 100 mm grid: the alias (100 mm) puts the shortest resolvable
        // period (250 mm) at half the travel, so none is left.
        let grid: Vec<f64> = (0..=5).map(|i| i as f64 * 100.0).collect();
        let r = periodic_reach(&grid, false);
        assert_eq!((r.positions, r.periods), (6, None));
        // (The first frequency of the scan past the threshold: within a few per cent.)
        assert!(r.alias.is_some_and(|a| (a - 100.0).abs() < 5.0), "{r:?}");
        assert!(periods_to_scan(&grid, false).is_empty());
        // Five positions: too few for any scan.
        let r = periodic_reach(&grid[..5], false);
        assert_eq!((r.positions, r.periods, r.alias), (5, None, None));
        // 24 angles 15° apart: harmonics 1 … 9 (9 × 2.5 × 15° ≤ 360°).
        let angles: Vec<f64> = (0..24).map(|i| (i as f64 * 15.0).to_radians()).collect();
        let r = periodic_reach(&angles, true);
        let (lo, hi) = r.periods.unwrap();
        assert!((std::f64::consts::TAU / lo - 9.0).abs() < 1e-9 && hi == std::f64::consts::TAU);
        assert_eq!(periods_to_scan(&angles, true).len(), 9);
    }

    #[test]
    fn irregular_targets_open_the_scan_below_the_mean_step() {
        // Steps of 20 mm ± 6 mm (hashed, irregular, as ISO 230-2 recommends):
        // no alias above 1 mm, so a 5 mm ball-screw pitch lies inside the scan.
        let x: Vec<f64> = (0..=40)
            .map(|i| {
                let uniform = splitmix64(i as u64) as f64 / u64::MAX as f64;
                let jitter = if i % 40 == 0 {
                    0.0
                } else {
                    12.0 * uniform - 6.0
                };
                i as f64 * 20.0 + jitter
            })
            .collect();
        assert_eq!(alias_period(&x, 1.0), None);
        assert_eq!(periodic_reach(&x, false).alias, None);
        let p = periods_to_scan(&x, false);
        assert!(p[0] < 5.0 && p[0] >= 1.0, "shortest period {}", p[0]);
    }
}

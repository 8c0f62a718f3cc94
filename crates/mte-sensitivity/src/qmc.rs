//! Sobol' low-discrepancy sequence (Gray-code order) with Matoušek linear matrix scrambling and a
//! random digital shift.
//!
//! Direction numbers: the published table of Joe & Kuo, `new-joe-kuo-6.21201` (S. Joe and
//! F. Y. Kuo, "Constructing Sobol sequences with better two-dimensional projections", SIAM J. Sci.
//! Comput. 30, 2635–2654, 2008; <https://web.maths.unsw.edu.au/~fkuo/sobol/>), its first 1000
//! dimensions, embedded as `data/new-joe-kuo-6.1000.txt`. That file is the copy Apache Commons Math
//! ships (`src/main/resources/assets/org/apache/commons/math4/random/new-joe-kuo-6.1000`),
//! reformatted to single spaces; every row was checked equal to the table SciPy 1.17 ships
//! (`scipy/stats/_sobol_direction_numbers.npz`, same source). Columns: dimension d, degree s,
//! coefficient word a of the primitive polynomial, initial direction numbers m₁…m_s.

use crate::error::{Error, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Largest supported dimension (the embedded Joe–Kuo table ends at dimension 1000).
pub const MAX_DIM: usize = 1000;
const BITS: usize = 32;

/// The first 1000 dimensions of `new-joe-kuo-6.21201` (header line, then `d s a m_1 … m_s`).
const JOE_KUO_TABLE: &str = include_str!("../data/new-joe-kuo-6.1000.txt");

/// One row of the Joe–Kuo table: degree s, coefficient word a, initial direction numbers m₁…m_s.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct JoeKuoRow {
    pub(crate) degree: u32,
    pub(crate) a: u32,
    pub(crate) m: Vec<u32>,
}

/// The parsed table, dimensions 2…[`MAX_DIM`] in order (parsed once, on first use).
pub(crate) fn joe_kuo_rows() -> &'static [JoeKuoRow] {
    static ROWS: std::sync::OnceLock<Vec<JoeKuoRow>> = std::sync::OnceLock::new();
    ROWS.get_or_init(|| {
        JOE_KUO_TABLE
            .lines()
            .skip(1)
            .filter(|l| !l.trim().is_empty())
            .enumerate()
            .map(|(row, line)| {
                let f: Vec<u32> = line
                    .split_whitespace()
                    .map(|t| t.parse().expect("embedded Joe–Kuo table: integer field"))
                    .collect();
                assert!(
                    f.len() >= 4 && f[0] as usize == row + 2 && f.len() == 3 + f[1] as usize,
                    "embedded Joe–Kuo table: malformed row {line:?}"
                );
                JoeKuoRow {
                    degree: f[1],
                    a: f[2],
                    m: f[3..].to_vec(),
                }
            })
            .collect()
    })
}

/// Unscrambled direction numbers V[d][i] = mᵢ·2^{32−i} (i = 1…32) for dimensions 0…dim−1: the
/// van der Corput sequence in dimension 0, the Joe–Kuo rows beyond, with the recurrence
/// mᵢ = 2a₁mᵢ₋₁ ⊕ 2²a₂mᵢ₋₂ ⊕ … ⊕ 2^{s−1}a_{s−1}mᵢ₋ₛ₊₁ ⊕ 2ˢmᵢ₋ₛ ⊕ mᵢ₋ₛ (Bratley & Fox).
///
/// # Panics
/// If `dim > MAX_DIM` (callers check).
pub(crate) fn direction_numbers(dim: usize) -> Vec<[u32; BITS]> {
    let rows = joe_kuo_rows();
    assert!(
        dim <= rows.len() + 1,
        "Sobol' dimension {dim} beyond the table"
    );
    let mut out = Vec::with_capacity(dim);
    let mut first = [0u32; BITS];
    for (i, v) in first.iter_mut().enumerate() {
        *v = 1u32 << (BITS - 1 - i);
    }
    out.push(first);
    for row in rows.iter().take(dim.saturating_sub(1)) {
        let s = row.degree as usize;
        let a = row.a as u64;
        let mut m = vec![0u64; BITS + 1];
        for (i, &mi) in row.m.iter().enumerate() {
            m[i + 1] = mi as u64;
        }
        for i in (s + 1)..=BITS {
            let mut v = m[i - s] ^ (m[i - s] << s);
            for kk in 1..s {
                if (a >> (s - 1 - kk)) & 1 == 1 {
                    v ^= m[i - kk] << kk;
                }
            }
            m[i] = v;
        }
        let mut vd = [0u32; BITS];
        for i in 1..=BITS {
            vd[i - 1] = ((m[i] << (BITS - i)) & 0xFFFF_FFFF) as u32;
        }
        out.push(vd);
    }
    out
}

/// A (possibly scrambled) Sobol' point set generator in `dim` dimensions.
#[derive(Debug, Clone)]
pub struct SobolSequence {
    dim: usize,
    v: Vec<[u32; BITS]>,
    shift: Vec<u32>,
}

impl SobolSequence {
    /// Unscrambled sequence (the first point is the origin).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] if `dim` is 0 or above [`MAX_DIM`].
    pub fn new(dim: usize) -> Result<Self> {
        if dim == 0 || dim > MAX_DIM {
            return Err(Error::InvalidParameter {
                name: "dim",
                message: format!("Sobol' sequence supports 1…{MAX_DIM} dimensions, got {dim}"),
            });
        }
        Ok(SobolSequence {
            dim,
            v: direction_numbers(dim),
            shift: vec![0; dim],
        })
    }

    /// Scrambled sequence: Matoušek's random linear matrix scramble (a random lower-triangular
    /// binary matrix with unit diagonal applied to the digits) plus a random digital shift, one
    /// per dimension, from a ChaCha8 stream seeded with `seed`.
    ///
    /// # Errors
    /// As [`SobolSequence::new`].
    pub fn scrambled(dim: usize, seed: u64) -> Result<Self> {
        let mut s = Self::new(dim)?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(0x50B0_1500);
        for d in 0..dim {
            let mut rows = [0u32; BITS];
            for (r, row) in rows.iter_mut().enumerate() {
                let high = if r == 0 { 0 } else { u32::MAX << (BITS - r) };
                *row = (rng.random::<u32>() & high) | (1u32 << (BITS - 1 - r));
            }
            for vj in s.v[d].iter_mut() {
                let mut out = 0u32;
                for (r, row) in rows.iter().enumerate() {
                    if (row & *vj).count_ones() & 1 == 1 {
                        out |= 1u32 << (BITS - 1 - r);
                    }
                }
                *vj = out;
            }
            s.shift[d] = rng.random::<u32>();
        }
        Ok(s)
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The integer digits (32 bits, most significant first) of point `n`, dimension `d`.
    pub fn point_bits(&self, n: u64, d: usize) -> u32 {
        let g = n ^ (n >> 1);
        let mut x = self.shift[d];
        for (j, vj) in self.v[d].iter().enumerate() {
            if g >> j & 1 == 1 {
                x ^= vj;
            }
        }
        x
    }

    /// Writes points `start … start + n_rows − 1` row-major into `out` (n_rows × dim), each
    /// coordinate (x + ½)/2³² so that it lies strictly inside (0, 1).
    ///
    /// # Panics
    /// If `out.len() != n_rows * dim` or the index exceeds 2³².
    pub fn fill(&self, start: u64, n_rows: usize, out: &mut [f64]) {
        assert_eq!(out.len(), n_rows * self.dim, "output buffer size");
        assert!(
            start + n_rows as u64 <= 1u64 << 32,
            "Sobol' index beyond 2^32"
        );
        if n_rows == 0 {
            return;
        }
        let mut x: Vec<u32> = (0..self.dim).map(|d| self.point_bits(start, d)).collect();
        const SCALE: f64 = 1.0 / 4_294_967_296.0;
        for r in 0..n_rows {
            let row = &mut out[r * self.dim..(r + 1) * self.dim];
            for (o, xi) in row.iter_mut().zip(&x) {
                *o = (*xi as f64 + 0.5) * SCALE;
            }
            let n = start + r as u64 + 1;
            if r + 1 < n_rows {
                let c = n.trailing_zeros() as usize;
                for (xi, v) in x.iter_mut().zip(&self.v) {
                    *xi ^= v[c];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// GF(2) polynomial product modulo `p` (degree `s`), bit i = coefficient of xⁱ.
    fn mulmod(a: u64, b: u64, p: u64, s: u32) -> u64 {
        let mut r = 0u64;
        let mut a = a;
        let mut b = b;
        while b != 0 {
            if b & 1 == 1 {
                r ^= a;
            }
            b >>= 1;
            a <<= 1;
            if a >> s & 1 == 1 {
                a ^= p;
            }
        }
        r
    }

    fn powmod(e: u64, p: u64, s: u32) -> u64 {
        let (mut base, mut e, mut r) = (2u64, e, 1u64); // base = x
        while e > 0 {
            if e & 1 == 1 {
                r = mulmod(r, base, p, s);
            }
            base = mulmod(base, base, p, s);
            e >>= 1;
        }
        r
    }

    /// Whether the degree-s polynomial with bit pattern `p` is primitive over GF(2).
    fn is_primitive(p: u64, s: u32) -> bool {
        if s == 1 {
            return p == 0b11;
        }
        let order = (1u64 << s) - 1;
        if powmod(order, p, s) != 1 {
            return false;
        }
        let mut n = order;
        let mut q = 2;
        let mut factors = vec![];
        while q * q <= n {
            if n % q == 0 {
                factors.push(q);
                while n % q == 0 {
                    n /= q;
                }
            }
            q += 1;
        }
        if n > 1 {
            factors.push(n);
        }
        factors.iter().all(|&f| powmod(order / f, p, s) != 1)
    }

    /// (degree, a) of the primitive polynomials for dimensions 2, 3, … (Joe–Kuo order): an
    /// independent enumeration the table's polynomial column is checked against.
    fn primitive_polynomials(count: usize) -> Vec<(u32, u32)> {
        let mut out = Vec::with_capacity(count);
        let mut s = 1u32;
        while out.len() < count {
            for a in 0..(1u32 << (s - 1)) {
                let p = (1u64 << s) | ((a as u64) << 1) | 1;
                if is_primitive(p, s) {
                    out.push((s, a));
                    if out.len() == count {
                        break;
                    }
                }
            }
            s += 1;
        }
        out
    }

    #[test]
    fn polynomials_match_joe_kuo_order() {
        // The table's polynomial column equals an independent enumeration of the primitive
        // polynomials (by degree, then coefficient word), and every initial mᵢ is odd and < 2ⁱ.
        let rows = joe_kuo_rows();
        assert_eq!(rows.len(), MAX_DIM - 1);
        let p = primitive_polynomials(rows.len());
        for (d, row) in rows.iter().enumerate() {
            assert_eq!(p[d], (row.degree, row.a), "dimension {}", d + 2);
            assert_eq!(row.m.len(), row.degree as usize);
            for (i, mi) in row.m.iter().enumerate() {
                assert!(mi % 2 == 1 && *mi < 1 << (i + 1), "dimension {}", d + 2);
            }
        }
        // Spot rows of new-joe-kuo-6.21201 (dimensions 2, 21, 1000 of the published file).
        assert_eq!(rows[0].m, [1]);
        assert_eq!(rows[19].m, [1, 3, 7, 13, 13, 15, 69]);
        assert_eq!(
            rows[998],
            JoeKuoRow {
                degree: 13,
                a: 3396,
                m: vec![1, 1, 3, 9, 3, 3, 105, 201, 373, 877, 919, 1263, 6649]
            }
        );
        // number of primitive polynomials of degree s is φ(2^s − 1)/s: 1,1,2,2,6,6,18,16,48,60
        let all = primitive_polynomials(160);
        for (s, cnt) in [
            (1, 1),
            (2, 1),
            (3, 2),
            (4, 2),
            (5, 6),
            (6, 6),
            (7, 18),
            (8, 16),
            (9, 48),
            (10, 60),
        ] {
            assert_eq!(all.iter().filter(|p| p.0 == s).count(), cnt, "degree {s}");
        }
    }

    #[test]
    fn first_points_match_the_known_sequence() {
        // Unscrambled Sobol' points 0…8, dimensions 1–3 (Bratley & Fox; the same values from
        // scipy.stats.qmc.Sobol(d=3, scramble=False).random(9)).
        let s = SobolSequence::new(3).unwrap();
        let expected = [
            [0.0, 0.0, 0.0],
            [0.5, 0.5, 0.5],
            [0.75, 0.25, 0.25],
            [0.25, 0.75, 0.75],
            [0.375, 0.375, 0.625],
            [0.875, 0.875, 0.125],
            [0.625, 0.125, 0.875],
            [0.125, 0.625, 0.375],
            [0.1875, 0.3125, 0.9375],
        ];
        for (n, row) in expected.iter().enumerate() {
            for (d, x) in row.iter().enumerate() {
                assert_eq!(
                    s.point_bits(n as u64, d) as f64 / 4_294_967_296.0,
                    *x,
                    "n={n} d={d}"
                );
            }
        }
    }

    /// The whole table against SciPy 1.17, which ships the same Joe–Kuo numbers: points of
    /// `qmc.Sobol(d=1000, scramble=False, bits=32).random(4096)` times 2³², spot values and the
    /// checksum Σₙ Σ_d bits(n, d)·(n + 1)·(d + 1) mod 2⁶⁴ over all 4096 × 1000 coordinates
    /// (computed there with Python integers).
    #[test]
    fn unscrambled_points_match_scipy() {
        let s = SobolSequence::new(MAX_DIM).unwrap();
        for (n, d, bits) in [
            (5u64, 20usize, 2_684_354_560u32),
            (7, 83, 2_684_354_560),
            (100, 500, 771_751_936),
            (1000, 999, 859_832_320),
            (1023, 41, 4_181_721_088),
            (37, 998, 1_811_939_328),
            (4095, 1, 4_042_260_480),
            (4095, 2, 1_435_500_544),
            (4095, 99, 4_134_535_168),
            (4095, 499, 4_031_774_720),
            (4095, 998, 3_647_995_904),
            (4095, 999, 1_324_351_488),
        ] {
            assert_eq!(s.point_bits(n, d), bits, "n={n} d={d}");
        }
        let mut sum = 0u64;
        for n in 0..4096u64 {
            for d in 0..MAX_DIM {
                let w = (n + 1).wrapping_mul(d as u64 + 1);
                sum = sum.wrapping_add((s.point_bits(n, d) as u64).wrapping_mul(w));
            }
        }
        assert_eq!(sum, 0xe3c5_753b_0000_0000);
    }

    /// Every one-dimensional projection of the first 2^m points is a (0, m, 1)-net: exactly one
    /// point per interval [j/2^m, (j+1)/2^m); scrambling preserves this.
    #[test]
    fn each_dimension_is_a_net() {
        for seq in [
            SobolSequence::new(90).unwrap(),
            SobolSequence::scrambled(90, 7).unwrap(),
        ] {
            let m = 10;
            let n = 1usize << m;
            let mut pts = vec![0.0; n * 90];
            seq.fill(0, n, &mut pts);
            for d in 0..90 {
                let mut seen = vec![false; n];
                for r in 0..n {
                    let cell = (pts[r * 90 + d] * n as f64) as usize;
                    assert!(!seen[cell], "dimension {d}: cell {cell} twice");
                    seen[cell] = true;
                }
            }
        }
    }

    /// Two-dimensional projections are balanced: 2^m points in 2^a × 2^b boxes (a + b ≤ m − t) hold
    /// equal counts, and scrambling preserves it. For the first 256 points of the Joe–Kuo table:
    /// 2 × 2 boxes in all pairs of the first 84 dimensions (a Saltelli design with k = 41), 4 × 4
    /// boxes in all pairs of the first 18 (dimensions 0 and 26 are the first pair that is not;
    /// both limits read off `scipy.stats.qmc.Sobol(d=84, scramble=False).random(256)`).
    #[test]
    fn two_dimensional_projections_balanced() {
        let dim = 84;
        let seq = SobolSequence::scrambled(dim, 3).unwrap();
        let n = 256;
        let mut pts = vec![0.0; n * dim];
        seq.fill(0, n, &mut pts);
        let balanced = |boxes: usize, i: usize, j: usize| {
            let mut cnt = vec![0usize; boxes * boxes];
            for r in 0..n {
                let a = (pts[r * dim + i] * boxes as f64) as usize;
                let b = (pts[r * dim + j] * boxes as f64) as usize;
                cnt[a * boxes + b] += 1;
            }
            cnt.iter().all(|&c| c == n / (boxes * boxes))
        };
        for (boxes, upto) in [(4usize, 18usize), (2, 84)] {
            for i in 0..upto {
                for j in (i + 1)..upto {
                    assert!(
                        balanced(boxes, i, j),
                        "dims {i},{j}, {boxes} × {boxes} boxes"
                    );
                }
            }
        }
        // The check discriminates: the first pair SciPy shows unbalanced in 4 × 4 boxes.
        assert!(!balanced(4, 0, 26));
    }

    #[test]
    fn fill_from_offset_equals_fill_from_zero() {
        let seq = SobolSequence::scrambled(5, 1).unwrap();
        let mut all = vec![0.0; 100 * 5];
        seq.fill(0, 100, &mut all);
        let mut part = vec![0.0; 37 * 5];
        seq.fill(41, 37, &mut part);
        assert_eq!(&all[41 * 5..78 * 5], &part[..]);
    }
}

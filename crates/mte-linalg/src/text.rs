//! Names in messages: the closest known names to a misspelt one.

/// The `k` names of `known` closest to `name` by edit distance (case-insensitive), closest
/// first, each once.
///
/// ```
/// let known = ["EXX poly3", "EYX poly3", "EC0Y", "EXX reversal"];
/// assert_eq!(mte_linalg::text::closest("EXX poly2", known.iter(), 2), ["EXX poly3", "EYX poly3"]);
/// ```
pub fn closest<S: AsRef<str>>(
    name: &str,
    known: impl IntoIterator<Item = S>,
    k: usize,
) -> Vec<String> {
    let low = name.to_lowercase();
    let mut scored: Vec<(usize, String)> = known
        .into_iter()
        .map(|n| {
            (
                levenshtein(&low, &n.as_ref().to_lowercase()),
                n.as_ref().to_string(),
            )
        })
        .collect();
    scored.sort();
    scored.dedup_by(|a, b| a.1 == b.1);
    scored.into_iter().take(k).map(|(_, n)| n).collect()
}

/// Edit distance on chars.
pub fn levenshtein(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for j in 0..b.len() {
            let above = row[j + 1];
            row[j + 1] = (diagonal + usize::from(ca != b[j]))
                .min(row[j] + 1)
                .min(above + 1);
            diagonal = above;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::levenshtein;

    #[test]
    fn levenshtein_counts_edits() {
        assert_eq!(levenshtein("kitten", "sitting"), 3);
        assert_eq!(levenshtein("", "abc"), 3);
        assert_eq!(levenshtein("EC0Y", "EC0Y"), 0);
    }
}

//! Text input and names in messages: reading a user's text file (regular files only, a UTF-8
//! byte-order mark dropped) and the closest known names to a misspelt one.

use std::io;
use std::path::Path;

/// Reads a user's text file: refuses anything but a regular file (a FIFO or device would block
/// or never end) and drops a leading UTF-8 byte-order mark, which editors on Windows write and
/// which JSON and CSV readers would otherwise reject as "expected value at line 1 column 1".
///
/// ```
/// let dir = std::env::temp_dir().join("mte-linalg-read-text-doc");
/// std::fs::create_dir_all(&dir).unwrap();
/// let path = dir.join("bom.json");
/// std::fs::write(&path, b"\xEF\xBB\xBF{}").unwrap();
/// assert_eq!(mte_linalg::text::read_text(&path).unwrap(), "{}");
/// assert!(mte_linalg::text::read_text(&dir).is_err());
/// ```
pub fn read_text(path: impl AsRef<Path>) -> io::Result<String> {
    let path = path.as_ref();
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "not a regular file (a directory, FIFO or device cannot be read as data)",
        ));
    }
    let text = std::fs::read_to_string(path)?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

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

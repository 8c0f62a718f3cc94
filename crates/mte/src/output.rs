//! The output folder of a command (`--out`): checked before any work, results written
//! atomically at the end, stale results of an earlier run removed.
//!
//! Every subcommand that writes files does it through [`OutDir`]:
//!
//! 1. [`OutDir::prepare`] runs first, before reading inputs or computing: a `--out` that names a
//!    file, or a folder that cannot be created or written, is an error at once.
//! 2. The command adds its files ([`OutDir::add`], [`OutDir::add_json`]); they are kept in
//!    memory, so a failure while computing or drawing a plot leaves the folder as it was.
//! 3. [`OutDir::commit`] writes each file under a temporary name (`.NAME.mte-tmp`) and renames
//!    them all once every write succeeded; then it removes the files that the previous run
//!    into this folder wrote and this one did not (listed in the folder's `.mte-outputs`), so
//!    the folder never mixes two runs. Files that mte did not write are never touched.
//!
//! ```
//! let dir = std::env::temp_dir().join(format!("mte-outdir-doc-{}", std::process::id()));
//! let mut out = mte::output::OutDir::prepare(&dir)?;
//! out.add("report.md", "# report\n");
//! out.commit()?;
//! assert_eq!(std::fs::read_to_string(dir.join("report.md")).unwrap(), "# report\n");
//! # std::fs::remove_dir_all(&dir).unwrap();
//! # Ok::<(), mte::CliError>(())
//! ```

use crate::CliError;
use std::path::{Path, PathBuf};

/// Name of the list of files the last run wrote into an output folder.
pub const MANIFEST: &str = ".mte-outputs";

/// An output folder and the files a command will write into it.
#[derive(Debug)]
pub struct OutDir {
    dir: PathBuf,
    files: Vec<(String, Vec<u8>)>,
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> CliError + '_ {
    move |source| CliError::Io {
        path: path.to_path_buf(),
        source,
    }
}

impl OutDir {
    /// Checks (and creates) the output folder before any work.
    ///
    /// # Errors
    /// [`CliError::Usage`] when `dir` exists and is not a folder; [`CliError::Io`] naming the
    /// folder when it cannot be created or written to.
    pub fn prepare(dir: &Path) -> Result<Self, CliError> {
        if let Ok(meta) = std::fs::metadata(dir)
            && !meta.is_dir()
        {
            return Err(CliError::Usage(format!(
                "--out {}: exists and is not a folder",
                dir.display()
            )));
        }
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        let probe = dir.join(format!(".mte-probe-{}", std::process::id()));
        std::fs::write(&probe, b"").map_err(io(dir))?;
        let _ = std::fs::remove_file(&probe);
        Ok(Self {
            dir: dir.to_path_buf(),
            files: Vec::new(),
        })
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Adds a file (a name relative to the folder, without `/`); a second file of the same
    /// name replaces the first.
    pub fn add(&mut self, name: impl Into<String>, content: impl Into<Vec<u8>>) {
        let name = name.into();
        let content = content.into();
        match self.files.iter_mut().find(|f| f.0 == name) {
            Some(f) => f.1 = content,
            None => self.files.push((name, content)),
        }
    }

    /// Adds `value` as pretty JSON with a trailing newline.
    ///
    /// # Errors
    /// [`CliError::Json`] naming the file when `value` cannot be serialised.
    pub fn add_json<T: serde::Serialize + ?Sized>(
        &mut self,
        name: &str,
        value: &T,
    ) -> Result<(), CliError> {
        let mut text = serde_json::to_string_pretty(value).map_err(|source| CliError::Json {
            path: self.dir.join(name),
            source,
        })?;
        text.push('\n');
        self.add(name, text);
        Ok(())
    }

    /// Writes the files atomically (temporary names renamed at the end) and removes the files
    /// an earlier run wrote here that this run did not. Returns the paths written.
    ///
    /// # Errors
    /// [`CliError::Io`] naming the file; the temporary files written so far are removed and
    /// the folder keeps the earlier run's results.
    pub fn commit(self) -> Result<Vec<PathBuf>, CliError> {
        let tmp = |name: &str| self.dir.join(format!(".{name}.mte-tmp"));
        let mut written = Vec::new();
        for (name, content) in &self.files {
            let t = tmp(name);
            if let Err(e) = std::fs::write(&t, content) {
                for n in written.iter().chain(std::iter::once(name)) {
                    let _ = std::fs::remove_file(tmp(n));
                }
                return Err(io(&self.dir.join(name))(e));
            }
            written.push(name.clone());
        }
        let old: Vec<String> = std::fs::read_to_string(self.dir.join(MANIFEST))
            .map(|s| s.lines().map(str::to_string).collect())
            .unwrap_or_default();
        let mut paths = Vec::new();
        for name in &written {
            let p = self.dir.join(name);
            std::fs::rename(tmp(name), &p).map_err(io(&p))?;
            paths.push(p);
        }
        for stale in old.iter().filter(|o| !written.contains(o)) {
            // only plain names that mte wrote: never a path out of the folder
            if !stale.is_empty() && !stale.contains(['/', '\\']) && stale != ".." {
                let _ = std::fs::remove_file(self.dir.join(stale));
            }
        }
        let list: String = written.iter().map(|n| format!("{n}\n")).collect();
        let m = self.dir.join(MANIFEST);
        std::fs::write(tmp(MANIFEST), list).map_err(io(&m))?;
        std::fs::rename(tmp(MANIFEST), &m).map_err(io(&m))?;
        Ok(paths)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("mte-outdir-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn a_file_as_out_is_refused_at_once() {
        let d = scratch("file");
        std::fs::create_dir_all(&d).unwrap();
        let f = d.join("taken");
        std::fs::write(&f, "x").unwrap();
        let err = OutDir::prepare(&f).unwrap_err().to_string();
        assert!(
            err.contains("taken") && err.contains("not a folder"),
            "{err}"
        );
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_rerun_removes_the_earlier_runs_files_and_keeps_the_users() {
        let d = scratch("rerun");
        let mut o = OutDir::prepare(&d).unwrap();
        o.add("a.svg", "1");
        o.add("b.svg", "1");
        o.commit().unwrap();
        std::fs::write(d.join("notes.txt"), "mine").unwrap();
        let mut o = OutDir::prepare(&d).unwrap();
        o.add("a.svg", "2");
        o.commit().unwrap();
        assert_eq!(std::fs::read_to_string(d.join("a.svg")).unwrap(), "2");
        assert!(!d.join("b.svg").exists(), "stale b.svg left");
        assert!(d.join("notes.txt").exists(), "a user's file removed");
        let left: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .filter(|n| n.contains("mte-tmp") || n.contains("probe"))
            .collect();
        assert!(left.is_empty(), "{left:?}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn nothing_is_written_before_commit() {
        let d = scratch("lazy");
        let mut o = OutDir::prepare(&d).unwrap();
        o.add("a.csv", "x");
        drop(o);
        assert!(!d.join("a.csv").exists());
        std::fs::remove_dir_all(&d).unwrap();
    }
}

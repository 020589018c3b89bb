//! The output folder of a run (`--out`), owned by the run: checked before the solve (a folder,
//! created when missing, that can be written), and at the end the files of an earlier run that
//! this run did not rewrite are removed — only files saddle itself listed in the folder's
//! manifest [`MANIFEST`], never anything else. Every file is added to the manifest as soon as
//! it is written, so an interrupted run's files are removed by the next run too.
//!
//! To keep the results of a run, give the next run another `--out`, or move the files away
//! (or delete `.saddle-files`: files it does not list are never touched).

use std::collections::HashSet;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The manifest: the files the last run into the folder wrote, one name a line.
pub const MANIFEST: &str = ".saddle-files";

/// An output folder that cannot be used, or a file that cannot be written.
#[derive(Debug, Error)]
pub enum OutError {
    /// `--out` is not a folder that can be written (checked before any solve).
    #[error("--out {path}: {message}")]
    Unusable {
        /// The folder as given.
        path: PathBuf,
        /// Why it cannot be used.
        message: String,
    },
    /// A file could not be written or removed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// A claimed output folder: where the run writes, what the earlier run left, what this run
/// wrote.
#[derive(Debug)]
pub struct OutDir {
    dir: PathBuf,
    /// The topmost folder this run created (removed again when the run writes nothing).
    created: Option<PathBuf>,
    /// The files the manifest listed when the run began.
    earlier: Vec<String>,
    /// The files this run wrote, in order.
    written: Vec<String>,
    /// The same, to look up.
    seen: HashSet<String>,
    /// The manifest, open for appending once the first file is written.
    manifest: Option<File>,
    /// A rank other than the root of a distributed run ([`OutDir::follow`]): it writes its own
    /// files into the folder, and the root keeps the manifest.
    follower: bool,
}

impl OutDir {
    /// Claims `dir` before any solve: an existing folder, or one created now, in which a file can
    /// be created. Errors: an empty path, an existing file, a folder that cannot be created or
    /// written. Nothing of an earlier run is removed yet ([`OutDir::finish`]).
    pub fn claim(dir: &Path) -> Result<Self, OutError> {
        let unusable = |message: String| OutError::Unusable { path: dir.to_path_buf(), message };
        if dir.as_os_str().is_empty() {
            return Err(unusable("an empty path: name an output folder".into()));
        }
        if dir.exists() && !dir.is_dir() {
            return Err(unusable("exists and is not a folder: name a folder (it is created when missing)".into()));
        }
        let created = dir.ancestors().take_while(|a| !a.as_os_str().is_empty() && !a.exists()).last();
        let created = created.map(Path::to_path_buf);
        std::fs::create_dir_all(dir).map_err(|e| unusable(format!("cannot create the folder: {e}")))?;
        let out = Self {
            dir: dir.to_path_buf(),
            created,
            earlier: Vec::new(),
            written: Vec::new(),
            seen: HashSet::new(),
            manifest: None,
            follower: false,
        };
        let probe = dir.join(format!(".saddle-probe-{}", std::process::id()));
        if let Err(e) = File::create(&probe).and_then(|_| std::fs::remove_file(&probe)) {
            out.abandon();
            return Err(unusable(format!("cannot write into the folder: {e}")));
        }
        let earlier = std::fs::read_to_string(dir.join(MANIFEST)).unwrap_or_default();
        let earlier = earlier.lines().filter(|n| is_plain_name(n)).map(str::to_string).collect();
        Ok(Self { earlier, ..out })
    }

    /// The folder another rank claimed, followed (theory §12): files are written into it, but
    /// the manifest and the clean-up are the claiming rank's ([`OutDir::wrote`],
    /// [`OutDir::finish`] and [`OutDir::abandon`] do nothing).
    pub fn follow(dir: &Path) -> Self {
        Self {
            dir: dir.to_path_buf(),
            created: None,
            earlier: Vec::new(),
            written: Vec::new(),
            seen: HashSet::new(),
            manifest: None,
            follower: true,
        }
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The path of file `name` in the folder.
    pub fn path(&self, name: &str) -> PathBuf {
        self.dir.join(name)
    }

    /// The files this run wrote so far, in order.
    pub fn written(&self) -> &[String] {
        &self.written
    }

    /// Records that file `name` (a plain name in the folder) was written: appended to the
    /// manifest at once (once per name).
    pub fn wrote(&mut self, name: &str) -> Result<(), OutError> {
        debug_assert!(is_plain_name(name), "{name}");
        if self.follower || self.seen.contains(name) {
            return Ok(());
        }
        let path = self.path(MANIFEST);
        let io = |source| OutError::Io { path: path.clone(), source };
        if self.manifest.is_none() {
            self.manifest = Some(OpenOptions::new().create(true).append(true).open(&path).map_err(io)?);
        }
        let file = self.manifest.as_mut().expect("opened above");
        writeln!(file, "{name}").map_err(io)?;
        self.written.push(name.to_string());
        self.seen.insert(name.to_string());
        Ok(())
    }

    /// The run is done: removes the files of the earlier run that this run did not rewrite, and
    /// leaves the manifest listing this run's files. Returns them, in the order written.
    pub fn finish(mut self) -> Result<Vec<String>, OutError> {
        if self.follower {
            return Ok(self.written);
        }
        for name in self.earlier.iter().filter(|n| !self.seen.contains(*n)) {
            let path = self.dir.join(name);
            match std::fs::remove_file(&path) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(OutError::Io { path, source: e }),
                _ => {}
            }
        }
        self.manifest = None;
        let (path, tmp) = (self.path(MANIFEST), self.path(".saddle-files.partial"));
        let text: String = self.written.iter().map(|n| format!("{n}\n")).collect();
        std::fs::write(&tmp, text)
            .and_then(|_| std::fs::rename(&tmp, &path))
            .map_err(|source| OutError::Io { path, source })?;
        Ok(self.written)
    }

    /// The run failed before writing anything: the folder is left as it was (removed again when
    /// this run created it and it is still empty).
    pub fn abandon(self) {
        debug_assert!(self.written.is_empty(), "abandon after writing {:?}", self.written);
        if let Some(top) = &self.created {
            // innermost first; a folder that is not empty stays
            for a in self.dir.ancestors().take_while(|a| a.starts_with(top)) {
                if std::fs::remove_dir(a).is_err() {
                    break;
                }
            }
        }
    }
}

/// A file name in the folder itself (no separator, not `.` or `..`, not the manifest).
fn is_plain_name(name: &str) -> bool {
    !name.is_empty() && name != "." && name != ".." && name != MANIFEST && !name.contains(['/', '\\'])
}

/// The files written, for a line `wrote DIR: …`: the numbered files of one stem
/// (`solution_0000.vtu` … `solution_0040.vtu`) shown as one entry with their count, where the
/// first of them was written.
pub fn describe(written: &[String]) -> String {
    type Group<'a> = (Option<(&'a str, &'a str)>, Vec<&'a str>);
    let mut parts: Vec<Group> = Vec::new();
    for name in written {
        let stem = numbered_stem(name);
        match parts.iter_mut().find(|(s, _)| stem.is_some() && *s == stem) {
            Some((_, names)) => names.push(name),
            None => parts.push((stem, vec![name])),
        }
    }
    let shown: Vec<String> = parts
        .into_iter()
        .flat_map(|(_, names)| match names.as_slice() {
            [first, .., last] if names.len() > 2 => vec![format!("{first} … {last} ({} files)", names.len())],
            _ => names.iter().map(|n| n.to_string()).collect(),
        })
        .collect();
    shown.join(", ")
}

/// `("solution_", ".vtu")` for `solution_0012.vtu`: a name whose last `_` is followed by digits.
fn numbered_stem(name: &str) -> Option<(&str, &str)> {
    let (head, tail) = name.rsplit_once('_')?;
    let digits = tail.find(|c: char| !c.is_ascii_digit()).unwrap_or(tail.len());
    (digits > 0).then(|| (head, &tail[digits..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbered_runs_are_shown_once() {
        let w: Vec<String> =
            ["solution_0000.vtu", "solution_0001.vtu", "solution_0002.vtu", "solution.pvd"].map(String::from).to_vec();
        assert_eq!(describe(&w), "solution_0000.vtu … solution_0002.vtu (3 files), solution.pvd");
    }
}

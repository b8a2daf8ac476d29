//! The runner's checkout and builds: one git worktree per runner (`<work>/<name>/checkout`,
//! detached, reused between jobs so that a build after a small change is incremental), built with
//! `cargo build --bins` into a target directory several runners may share, and a cache of built
//! `tessera` binaries keyed by the commit's build inputs.
//!
//! The key is the commit's tree without `scenarios/`, `dashboard/`, `ci/` and top-level Markdown:
//! commits that change only scenario files (or the dashboard, or docs) share one build. Builds
//! into a shared target directory hold an exclusive lock on `<target>/tessera-runner.lock` from
//! `cargo build` to the copy of the binary, so another runner's build cannot replace it between.
//! Not for: running scenarios (see [`super::job`]).

use std::path::{Path, PathBuf};
use std::process::Command;

use sha2::{Digest, Sha256};

#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    #[error("git {args}: {message}")]
    Git { args: String, message: String },
    #[error("{commit} does not build: {message}")]
    Build { commit: String, message: String },
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> BuildError + '_ {
    move |source| BuildError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Runs git in `dir`; its stdout, trimmed.
pub fn git(dir: &Path, args: &[&str]) -> Result<String, BuildError> {
    let out = Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(args)
        .output()
        .map_err(|e| BuildError::Git {
            args: args.join(" "),
            message: e.to_string(),
        })?;
    if !out.status.success() {
        return Err(BuildError::Git {
            args: args.join(" "),
            message: String::from_utf8_lossy(&out.stderr).trim().to_string(),
        });
    }
    Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// Top-level entries that do not go into the `tessera` binary.
const NOT_BUILT: &[&str] = &["scenarios", "dashboard", "ci", ".github"];

/// The build key of `commit`: SHA-256 of its top-level tree listing without [`NOT_BUILT`] and
/// Markdown files.
pub fn build_key(repo: &Path, commit: &str) -> Result<String, BuildError> {
    let listing = git(repo, &["ls-tree", commit])?;
    let mut h = Sha256::new();
    for line in listing.lines() {
        let name = line.split('\t').nth(1).unwrap_or("");
        if NOT_BUILT.contains(&name) || name.ends_with(".md") {
            continue;
        }
        h.update(line.as_bytes());
        h.update(b"\n");
    }
    Ok(h.finalize()[..12]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect())
}

/// A runner's worktree, target directory and binary cache.
pub struct Workspace {
    pub repo: PathBuf,
    pub checkout: PathBuf,
    pub target: PathBuf,
    /// Builds made by this process (for the log and the acceptance script).
    pub builds: usize,
}

impl Workspace {
    /// Creates the worktree on first use.
    pub fn open(repo: &Path, work: &Path, target: &Path) -> Result<Workspace, BuildError> {
        std::fs::create_dir_all(work).map_err(io(work))?;
        std::fs::create_dir_all(target).map_err(io(target))?;
        let checkout = work.join("checkout");
        if !checkout.join(".git").exists() {
            let _ = git(repo, &["worktree", "prune"]);
            git(
                repo,
                &[
                    "worktree",
                    "add",
                    "--detach",
                    &checkout.to_string_lossy(),
                    "HEAD",
                ],
            )?;
        }
        Ok(Workspace {
            repo: repo.to_path_buf(),
            checkout,
            target: target.to_path_buf(),
            builds: 0,
        })
    }

    /// The full hash of `rev` in the repository.
    pub fn resolve(&self, rev: &str) -> Result<String, BuildError> {
        git(
            &self.repo,
            &["rev-parse", "--verify", &format!("{rev}^{{commit}}")],
        )
    }

    /// First-parent commits after `good` up to `bad`, oldest first.
    pub fn first_parent(&self, good: &str, bad: &str) -> Result<Vec<String>, BuildError> {
        let out = git(
            &self.repo,
            &[
                "rev-list",
                "--first-parent",
                "--reverse",
                &format!("{good}..{bad}"),
            ],
        )?;
        Ok(out.lines().map(str::to_string).collect())
    }

    /// Checks `commit` out in the worktree (scenario files come from here).
    pub fn checkout(&self, commit: &str) -> Result<(), BuildError> {
        git(
            &self.checkout,
            &["checkout", "--detach", "--force", "--quiet", commit],
        )?;
        Ok(())
    }

    /// The `tessera` binary of `commit`: from the cache when a commit with the same build key was
    /// built, else checked out and built. Leaves `commit` checked out.
    pub fn binary(&mut self, commit: &str) -> Result<PathBuf, BuildError> {
        let key = build_key(&self.repo, commit)?;
        let cached = self.target.join("tessera-bins").join(&key).join("tessera");
        self.checkout(commit)?;
        if cached.exists() {
            return Ok(cached);
        }
        let lock_path = self.target.join("tessera-runner.lock");
        let lock = std::fs::File::create(&lock_path).map_err(io(&lock_path))?;
        lock_exclusive(&lock).map_err(io(&lock_path))?;
        if cached.exists() {
            return Ok(cached);
        }
        let out = Command::new("cargo")
            .args(["build", "--bins", "--quiet", "--target-dir"])
            .arg(&self.target)
            .current_dir(&self.checkout)
            .output()
            .map_err(io(&self.checkout))?;
        if !out.status.success() {
            let stderr = String::from_utf8_lossy(&out.stderr);
            let tail: Vec<&str> = stderr.lines().rev().take(30).collect();
            return Err(BuildError::Build {
                commit: commit.into(),
                message: tail.into_iter().rev().collect::<Vec<_>>().join("\n"),
            });
        }
        self.builds += 1;
        let built = self.target.join("debug").join("tessera");
        let dir = cached.parent().expect("cached binary has a folder");
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        let tmp = dir.join("tessera.tmp");
        std::fs::copy(&built, &tmp).map_err(io(&built))?;
        std::fs::rename(&tmp, &cached).map_err(io(&cached))?;
        Ok(cached)
        // `lock` is released when dropped here.
    }
}

/// An exclusive `flock` on `file`, waited for.
fn lock_exclusive(file: &std::fs::File) -> std::io::Result<()> {
    use std::os::unix::io::AsRawFd;
    // SAFETY: flock on a file descriptor this function borrows for the call; no memory is shared.
    let rc = unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX) };
    if rc == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

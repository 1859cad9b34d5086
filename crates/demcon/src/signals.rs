//! `demcon run` stopped by SIGINT (Ctrl-C) or SIGTERM: it removes what it had half written
//! and exits with 130 or 143 (128 + the signal), as a shell reports a process killed by it.
//!
//! The outputs are written into a hidden sibling folder `.OUT.partial-PID` that then replaces
//! `OUT`, the earlier run's folder set aside meanwhile as `.OUT.old-PID`
//! (`demcon_scene::write_outputs`). A signal used to kill the process with the partial
//! folder left behind. Now the signal is taken by a thread of ours (signal-hook's self-pipe:
//! the handler only writes a byte, so the thread may remove folders), which
//! - removes the partial folder (again, should the writer recreate part of it meanwhile);
//! - puts the earlier run's folder back when the swap was half done (`OUT` gone, the old one
//!   set aside), or removes the set-aside copy when the new folder is already in place;
//! - removes a checkpoint's temporary file `OUT.checkpoint.tmp` and the write test files, but
//!   never the checkpoint itself: it is what `--resume` continues from (docs/scenes.md,
//!   "Long runs");
//! - says what it did, and exits; the main thread, should it finish meanwhile (its writing
//!   fails once the folder is gone), waits for it ([`hold_if_stopping`]).
//!
//! The folder names follow `demcon_scene::output`'s (`split_dir`, `write_outputs`,
//! `check_output_dir`); the CLI tests in `tests/cli_signals.rs` check that none is left.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

/// What a run leaves beside its output folder while it works, to clean up on a signal.
#[derive(Debug, Clone)]
pub struct RunFiles {
    /// The output folder `OUT`.
    pub out: PathBuf,
    /// The checkpoint file `OUT.checkpoint` (kept).
    pub checkpoint: PathBuf,
}

impl RunFiles {
    /// The parent folder and the name of the output folder, as `demcon_scene::output` takes
    /// them.
    fn parent_and_name(&self) -> Option<(PathBuf, std::ffi::OsString)> {
        let name = self.out.file_name()?.to_os_string();
        let parent = match self.out.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        Some((parent, name))
    }

    /// `.OUT.<what>-PID` beside the output folder.
    fn sibling(&self, what: &str) -> Option<PathBuf> {
        let (parent, name) = self.parent_and_name()?;
        let mut n = std::ffi::OsString::from(".");
        n.push(name);
        n.push(format!(".{what}-{}", std::process::id()));
        Some(parent.join(n))
    }

    /// Removes what an interrupted run leaves: the partial output folder, a half-done swap
    /// with the earlier run's folder, a checkpoint's temporary file, the write test files.
    /// Returns what it did, in words.
    pub fn clean_up(&self) -> Vec<String> {
        let mut did = Vec::new();
        if let Some(partial) = self.sibling("partial") {
            // The writer may still be creating files in it: remove until it stays gone.
            let mut removed = false;
            for _ in 0..200 {
                // Not found: nothing (left) to remove; another failure: a file appeared while
                // the folder was emptied, try again.
                removed |= std::fs::remove_dir_all(&partial).is_ok();
                if !partial.exists() {
                    break;
                }
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
            if removed {
                did.push(format!("removed the unfinished outputs {}", partial.display()));
            }
        }
        if let Some(old) = self.sibling("old")
            && old.exists()
        {
            if self.out.exists() {
                // The new folder is in place: the earlier one was on its way out.
                let _ = std::fs::remove_dir_all(&old);
            } else if std::fs::rename(&old, &self.out).is_ok() {
                did.push(format!("put the earlier run's {} back", self.out.display()));
            }
        }
        let mut tmp = self.checkpoint.as_os_str().to_os_string();
        tmp.push(".tmp");
        let _ = std::fs::remove_file(PathBuf::from(tmp));
        if let Some((parent, _)) = self.parent_and_name() {
            let probe = format!(".demcon-write-test-{}-", std::process::id());
            for entry in std::fs::read_dir(&parent).into_iter().flatten().flatten() {
                if entry.file_name().to_string_lossy().starts_with(&probe) {
                    let _ = std::fs::remove_file(entry.path());
                }
            }
        }
        if self.checkpoint.exists() {
            did.push(format!(
                "kept the checkpoint {} (continue with --resume)",
                self.checkpoint.display()
            ));
        }
        did
    }
}

/// Set by the signal thread before it cleans up: the main thread must not exit meanwhile.
static STOPPING: AtomicBool = AtomicBool::new(false);

/// Called by `main` before it reports and exits: while a signal is being handled (the run's
/// outputs being removed), waits for the signal thread to end the process, so that neither
/// an exit code nor an error of the half-removed writing ("No such file or directory")
/// overtakes it.
pub fn hold_if_stopping() {
    if STOPPING.load(Ordering::SeqCst) {
        loop {
            std::thread::park();
        }
    }
}

/// The exit code of a run stopped by signal `sig`: 128 + its number (130 for SIGINT, 143 for
/// SIGTERM).
pub fn exit_code(sig: i32) -> i32 {
    128 + sig
}

/// From now on, SIGINT and SIGTERM make the process clean up `files` and exit with
/// [`exit_code`]. Errors: the handlers cannot be installed.
#[cfg(unix)]
pub fn clean_up_on_signals(files: RunFiles, silent: bool) -> anyhow::Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    use signal_hook::iterator::Signals;

    let mut signals = Signals::new([SIGINT, SIGTERM])?;
    std::thread::Builder::new()
        .name("demcon-signals".into())
        .spawn(move || {
            if let Some(sig) = signals.forever().next() {
                STOPPING.store(true, Ordering::SeqCst);
                let did = files.clean_up();
                if !silent {
                    let name = if sig == SIGINT { "SIGINT" } else { "SIGTERM" };
                    let what = if did.is_empty() {
                        "no outputs written".to_string()
                    } else {
                        did.join("; ")
                    };
                    // After the progress line, on a line of its own.
                    eprintln!("\ninterrupted by {name}: {what}");
                }
                std::process::exit(exit_code(sig));
            }
        })?;
    Ok(())
}

/// No signals to catch here: a stopped run is killed as before.
#[cfg(not(unix))]
pub fn clean_up_on_signals(_files: RunFiles, _silent: bool) -> anyhow::Result<()> {
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("demcon-signals-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn files(d: &Path) -> RunFiles {
        RunFiles {
            out: d.join("out"),
            checkpoint: d.join("out.checkpoint"),
        }
    }

    #[test]
    fn the_partial_folder_goes_and_the_checkpoint_stays() {
        let d = scratch("partial");
        let f = files(&d);
        let partial = f.sibling("partial").unwrap();
        assert_eq!(partial, d.join(format!(".out.partial-{}", std::process::id())));
        std::fs::create_dir_all(partial.join("plots")).unwrap();
        std::fs::write(partial.join("particles_0000.vtu"), "x").unwrap();
        std::fs::write(&f.checkpoint, "ck").unwrap();
        std::fs::write(d.join("out.checkpoint.tmp"), "half").unwrap();
        let did = f.clean_up();
        assert!(!partial.exists());
        assert!(f.checkpoint.exists() && !d.join("out.checkpoint.tmp").exists());
        assert!(!f.out.exists());
        assert!(
            did.iter().any(|s| s.contains("removed the unfinished")),
            "{did:?}"
        );
        assert!(did.iter().any(|s| s.contains("kept the checkpoint")), "{did:?}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_half_done_swap_puts_the_earlier_run_back() {
        let d = scratch("swap");
        let f = files(&d);
        // Stopped between setting the earlier folder aside and renaming the new one.
        let (partial, old) = (f.sibling("partial").unwrap(), f.sibling("old").unwrap());
        std::fs::create_dir_all(&partial).unwrap();
        std::fs::create_dir_all(&old).unwrap();
        std::fs::write(old.join("summary.json"), "earlier").unwrap();
        f.clean_up();
        assert_eq!(
            std::fs::read_to_string(f.out.join("summary.json")).unwrap(),
            "earlier"
        );
        assert!(!partial.exists() && !old.exists());
        // Stopped after the new folder took its place: the set-aside one goes.
        std::fs::create_dir_all(&old).unwrap();
        f.clean_up();
        assert!(f.out.exists() && !old.exists());
        assert_eq!(exit_code(2), 130);
        assert_eq!(exit_code(15), 143);
        std::fs::remove_dir_all(&d).unwrap();
    }
}

//! Unit tests' scratch folders: one per test and process, removed when dropped (a failing
//! test's too, as its panic unwinds), so that runs leave nothing behind in the temp folder.

use std::path::{Path, PathBuf};

/// `temp_dir()/contrastxr-NAME-PID`, empty at creation, removed on drop.
pub struct ScratchDir(PathBuf);

impl ScratchDir {
    pub fn new(name: &str) -> Self {
        let pid = std::process::id();
        let dir = std::env::temp_dir().join(format!("contrastxr-{name}-{pid}"));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("a scratch folder in the temp folder");
        Self(dir)
    }
}

impl std::ops::Deref for ScratchDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for ScratchDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[cfg(test)]
mod tests {
    use super::ScratchDir;

    #[test]
    fn the_folder_goes_with_its_guard() {
        let scratch = ScratchDir::new("scratch-self");
        std::fs::create_dir_all(scratch.join("a/b")).unwrap();
        std::fs::write(scratch.join("a/b/c"), b"x").unwrap();
        let path = scratch.to_path_buf();
        drop(scratch);
        assert!(!path.exists());
        // Even when the test holding it fails.
        let path = std::panic::catch_unwind(|| {
            let scratch = ScratchDir::new("scratch-panic");
            std::fs::write(scratch.join("f"), b"x").unwrap();
            let path = scratch.to_path_buf();
            std::panic::panic_any(path);
        })
        .unwrap_err()
        .downcast::<std::path::PathBuf>()
        .unwrap();
        assert!(!path.exists());
    }
}

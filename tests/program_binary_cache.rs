//! The OpenGL program binary cache's file keeps what every writer kept: the layer's build
//! thread, the app's context and other processes each write it, and a save merges with what
//! the file holds by then (read under the file's lock) rather than dropping the others'
//! binaries.

use contrastxr::gpu::opengl::BinaryCache;
use std::collections::HashSet;
use std::path::Path;

#[test]
fn two_writers_keep_each_others_binaries() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("program-binary-cache");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // The only test of this binary: no other thread reads the environment meanwhile.
    std::env::set_var("XDG_CACHE_HOME", &dir);
    let driver = "Test vendor | test renderer | 4.5 Mesa 25.0.7";
    // Both read the (empty) file before either writes, as two builds running side by side.
    let mut first = BinaryCache::load(driver, true);
    let mut second = BinaryCache::load(driver, true);
    first.keep(1, 0x8741, vec![1, 2, 3]);
    second.keep(2, 0x8741, vec![4, 5]);
    // The sources of this build: the binaries' hashes.
    let current = || HashSet::from([1, 2, 3]);
    first.save(current());
    second.save(current());
    let file = BinaryCache::load(driver, true);
    assert_eq!(
        file.get(1),
        Some((0x8741, &[1u8, 2, 3][..])),
        "the first's binary was lost"
    );
    assert_eq!(
        file.get(2),
        Some((0x8741, &[4u8, 5][..])),
        "the second's binary was lost"
    );
    // A binary of sources this build no longer has is still dropped at a save.
    let mut third = BinaryCache::load(driver, true);
    third.keep(3, 0x8741, vec![6]);
    third.save(HashSet::from([2, 3]));
    let file = BinaryCache::load(driver, true);
    assert_eq!(file.get(1), None);
    assert!(file.get(2).is_some() && file.get(3).is_some());
}

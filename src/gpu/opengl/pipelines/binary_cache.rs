//! Linked program binaries (glGetProgramBinary) kept beside the Vulkan pipeline cache: one file
//! per driver (its GL_VENDOR, GL_RENDERER and GL_VERSION) in the same folder, read and written
//! as that cache's files are (gpu/core/cache_files.rs: a regular file of bounded size opened
//! without following links, the same length and checksum header, written atomically, other
//! drivers' files removed when old). A file that is damaged or written for another driver is
//! ignored and replaced; a binary the driver refuses is compiled again. The cache is only ever
//! an optimisation.

use crate::gpu::core::cache_files;
use crate::gpu::opengl::device::functions::{self as gl, Gl};
use std::collections::{HashMap, HashSet};

/// The data starts with this, then the driver string's length and bytes, the entry count,
/// and per entry: source hash (u64), binary format (u32), length (u32), bytes.
const MAGIC: &[u8; 8] = b"CXRGLPB1";

/// Binaries of some programs (source hash, binary format, bytes), handed from one engine to
/// another of the same driver: from a build thread's context to the app's, in memory.
#[derive(Debug, Default, Clone)]
pub struct ProgramBinaries(Vec<(u64, u32, Vec<u8>)>);

pub struct BinaryCache {
    driver: String,
    /// Whether the driver gives binaries at all.
    enabled: bool,
    entries: HashMap<u64, (u32, Vec<u8>)>,
    /// Entries were added since the file was read.
    changed: bool,
}

/// FNV-1a of a program's source (its key in the cache) or of the driver string.
pub fn source_hash(source: &str) -> u64 {
    source.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The file's name: "pipelines-gl-" and a hash of the driver string, so the pipeline
/// cache's clean-up of other drivers' files covers it.
fn file_name(driver: &str) -> String {
    format!("pipelines-gl-{:016x}.bin", source_hash(driver))
}

/// The entries of a file's data, if it is whole and for `driver`.
pub fn parse(data: &[u8], driver: &str) -> Result<HashMap<u64, (u32, Vec<u8>)>, String> {
    let mut at = 0usize;
    let mut take = |n: usize| -> Result<&[u8], String> {
        let end = at.checked_add(n).filter(|&e| e <= data.len());
        let end = end.ok_or("truncated")?;
        let s = &data[at..end];
        at = end;
        Ok(s)
    };
    if take(8)? != MAGIC {
        return Err("not a contrastxr program binary cache".into());
    }
    let u32_of = |b: &[u8]| u32::from_le_bytes(b.try_into().expect("4 bytes"));
    let len = u32_of(take(4)?) as usize;
    if take(len)? != driver.as_bytes() {
        return Err("written for another driver".into());
    }
    let count = u32_of(take(4)?);
    let mut entries = HashMap::new();
    for _ in 0..count {
        let hash = u64::from_le_bytes(take(8)?.try_into().expect("8 bytes"));
        let format = u32_of(take(4)?);
        let len = u32_of(take(4)?) as usize;
        entries.insert(hash, (format, take(len)?.to_vec()));
    }
    if take(1).is_ok() {
        return Err("trailing bytes".into());
    }
    Ok(entries)
}

fn data_of(driver: &str, entries: &HashMap<u64, (u32, Vec<u8>)>) -> Vec<u8> {
    let mut out = MAGIC.to_vec();
    out.extend_from_slice(&(driver.len() as u32).to_le_bytes());
    out.extend_from_slice(driver.as_bytes());
    out.extend_from_slice(&(entries.len() as u32).to_le_bytes());
    let mut keys: Vec<_> = entries.keys().copied().collect();
    keys.sort();
    for k in keys {
        let (format, bytes) = &entries[&k];
        out.extend_from_slice(&k.to_le_bytes());
        out.extend_from_slice(&format.to_le_bytes());
        out.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        out.extend_from_slice(bytes);
    }
    out
}

/// The data of a whole file: the pipeline cache's header (magic, length, checksum) checked
/// by writing it again.
fn unwrap_file(bytes: &[u8]) -> Option<&[u8]> {
    let data = bytes.get(24..)?;
    (cache_files::file_bytes(data) == bytes).then_some(data)
}

/// The entries of the driver's file (none where it is unreadable, damaged or foreign).
fn read_entries(driver: &str, enabled: bool) -> HashMap<u64, (u32, Vec<u8>)> {
    let path = cache_files::directory().map(|d| d.join(file_name(driver)));
    match path.filter(|_| enabled).map(|p| cache_files::read_file(&p)) {
        Some(Ok(Some(bytes))) => entries_in(&bytes, driver),
        _ => HashMap::new(),
    }
}

/// The entries of a whole file's `bytes` (none where it is damaged or foreign).
fn entries_in(bytes: &[u8], driver: &str) -> HashMap<u64, (u32, Vec<u8>)> {
    unwrap_file(bytes)
        .and_then(|data| parse(data, driver).ok())
        .unwrap_or_default()
}

impl BinaryCache {
    /// The driver's file, read now (an unreadable or foreign one counts as empty).
    pub fn load(driver: &str, enabled: bool) -> BinaryCache {
        BinaryCache {
            driver: driver.to_string(),
            enabled,
            entries: read_entries(driver, enabled),
            changed: false,
        }
    }

    /// Reads the file again, keeping this process's entries where both have one.
    pub fn reload(&mut self) {
        for (hash, entry) in read_entries(&self.driver, self.enabled) {
            self.entries.entry(hash).or_insert(entry);
        }
    }

    pub fn get(&self, hash: u64) -> Option<(u32, &[u8])> {
        self.entries.get(&hash).map(|(f, b)| (*f, b.as_slice()))
    }

    /// The entries of `hashes` this cache holds.
    pub fn binaries(&self, hashes: impl Iterator<Item = u64>) -> ProgramBinaries {
        let held = hashes.filter_map(|h| self.entries.get(&h).map(|(f, b)| (h, *f, b.clone())));
        ProgramBinaries(held.collect())
    }

    /// Takes in `binaries` where this cache has none of its own, as a read of the file would
    /// (they are not written again by this cache's next save).
    pub fn take_in(&mut self, binaries: ProgramBinaries) {
        for (hash, format, bytes) in binaries.0 {
            if self.enabled {
                self.entries.entry(hash).or_insert((format, bytes));
            }
        }
    }

    /// Drops an entry the driver refused.
    pub fn forget(&mut self, hash: u64) {
        self.changed |= self.entries.remove(&hash).is_some();
    }

    /// Keeps a linked program's binary under its source's hash.
    pub fn store(&mut self, g: &Gl, program: u32, hash: u64) {
        if !self.enabled {
            return;
        }
        let mut len = 0;
        // SAFETY: a linked program of this context; a valid output.
        unsafe { (g.get_programiv)(program, gl::PROGRAM_BINARY_LENGTH, &mut len) };
        if len <= 0 {
            return;
        }
        let mut bytes = vec![0u8; len as usize];
        let (mut written, mut format) = (0, 0);
        // SAFETY: the buffer holds `len` bytes, what GL said the binary needs.
        unsafe {
            (g.get_program_binary)(
                program,
                len,
                &mut written,
                &mut format,
                bytes.as_mut_ptr().cast(),
            )
        };
        bytes.truncate(written.clamp(0, len) as usize);
        self.keep(hash, format, bytes);
    }

    /// Keeps a binary (of `format`) under its source's hash, to be written at the next save.
    pub fn keep(&mut self, hash: u64, format: u32, bytes: Vec<u8>) {
        if self.enabled && !bytes.is_empty() {
            self.entries.insert(hash, (format, bytes));
            self.changed = true;
        }
    }

    /// Writes the file if entries were added (atomically, under the file's lock; see
    /// gpu/core/cache_files.rs `merge_atomically`), merged with what the file holds at that
    /// moment (another process, or a build thread of this one, may have written it since it
    /// was read; its entries are kept where this cache has none), with only the entries of
    /// `current` (the sources of this build: a changed shader's old binaries are dropped, so
    /// the file does not grow from build to build).
    pub fn save(&mut self, current: HashSet<u64>) {
        if !self.changed {
            return;
        }
        self.changed = false;
        self.entries.retain(|hash, _| current.contains(hash));
        let Some(dir) = cache_files::directory() else {
            return;
        };
        let name = file_name(&self.driver);
        let (driver, mut entries) = (self.driver.clone(), self.entries.clone());
        let merge = move |now: Option<Vec<u8>>| {
            let held = now.map(|bytes| entries_in(&bytes, &driver));
            for (hash, entry) in held.unwrap_or_default() {
                if current.contains(&hash) {
                    entries.entry(hash).or_insert(entry);
                }
            }
            cache_files::file_bytes(&data_of(&driver, &entries))
        };
        if cache_files::merge_atomically(&dir, &name, merge).is_ok() {
            cache_files::remove_old_foreign(&dir, &name);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_round_trip_and_damage_is_refused() {
        let mut entries = HashMap::new();
        entries.insert(7u64, (0x8741u32, vec![1u8, 2, 3]));
        entries.insert(9u64, (1u32, vec![]));
        let data = data_of("Mesa | llvmpipe | 4.5", &entries);
        let file = cache_files::file_bytes(&data);
        let back = parse(unwrap_file(&file).unwrap(), "Mesa | llvmpipe | 4.5").unwrap();
        assert_eq!(back, entries);
        assert!(parse(&data, "another driver").is_err());
        for cut in 0..data.len() {
            assert!(
                parse(&data[..cut], "Mesa | llvmpipe | 4.5").is_err(),
                "cut at {cut}"
            );
        }
        let mut flipped = file.clone();
        *flipped.last_mut().unwrap() ^= 1;
        assert!(unwrap_file(&flipped).is_none());
    }
}

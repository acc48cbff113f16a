//! The VkPipelineCache the engine builds its pipelines with: one file per device kind (its
//! pipelineCacheUUID) under `$XDG_CACHE_HOME/contrastxr` (default `~/.cache/contrastxr`), and
//! in memory for the whole process, so a second session of an app starts from what the first
//! one built even when it creates a new VkDevice. A file that is corrupt, truncated or written
//! for another device is ignored and replaced; the cache is only ever an optimisation.

use crate::gpu::core::cache_files::{
    self, directory, file_bytes, read_file, remove_old_foreign, write_atomically,
};
use crate::gpu::vulkan::device::{DeviceKind, GpuDevice, GpuError, VkResultExt};
use ash::vk;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Mutex, OnceLock};

/// The driver's own header (VkPipelineCacheHeaderVersionOne): length, version, vendor,
/// device, pipelineCacheUUID.
const VK_HEADER: usize = 16 + vk::UUID_SIZE;

/// The cache file of a kind of device.
fn file_name(key: &DeviceKind) -> String {
    let uuid: String = key.uuid.iter().map(|b| format!("{b:02x}")).collect();
    format!("pipelines-{uuid}.bin")
}

/// Whether `data` (vkGetPipelineCacheData's output) was written for a device of kind `key`.
fn written_for(key: &DeviceKind, data: &[u8]) -> bool {
    let word = |k: usize| {
        data.get(4 * k..4 * k + 4)
            .map(|b| u32::from_le_bytes(b.try_into().unwrap()))
    };
    data.len() >= VK_HEADER
        && word(0).is_some_and(|n| n as usize >= VK_HEADER && n as usize <= data.len())
        && word(1) == Some(vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32)
        && word(2) == Some(key.vendor)
        && word(3) == Some(key.device)
        && data[16..VK_HEADER] == key.uuid
}

/// The data of a cache file, if it is whole and for this device.
pub fn parse_file(bytes: &[u8], key: &DeviceKind) -> Result<Vec<u8>, String> {
    let data = cache_files::file_data(bytes)?;
    if !written_for(key, data) {
        return Err("written for another device or driver".into());
    }
    Ok(data.to_vec())
}

/// The newest data per device kind, shared by the sessions of this process.
fn in_memory() -> std::sync::MutexGuard<'static, HashMap<DeviceKind, Vec<u8>>> {
    static MEMORY: OnceLock<Mutex<HashMap<DeviceKind, Vec<u8>>>> = OnceLock::new();
    let m = MEMORY.get_or_init(Default::default);
    // Only map operations happen under this lock.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Where the data a cache starts with came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    /// Built by an earlier session of this process.
    Process,
    /// Read from this file.
    File(PathBuf),
    /// Nothing usable: empty. With why a file there was not used (None: there was none).
    Empty(Option<String>),
}

/// A device's VkPipelineCache and what it started from.
pub struct PipelineCache {
    pub(super) raw: vk::PipelineCache,
    pub key: DeviceKind,
    pub origin: Origin,
    /// Bytes of data it started with.
    pub loaded_bytes: usize,
}

/// The data to start from: this process's, else the file's, else none (and why).
fn initial_data(key: &DeviceKind) -> (Vec<u8>, Origin) {
    if let Some(data) = in_memory().get(key) {
        return (data.clone(), Origin::Process);
    }
    let Some(path) = directory().map(|d| d.join(file_name(key))) else {
        return (Vec::new(), Origin::Empty(None));
    };
    match read_file(&path) {
        Ok(Some(bytes)) => match parse_file(&bytes, key) {
            Ok(data) => (data, Origin::File(path)),
            Err(why) => (
                Vec::new(),
                Origin::Empty(Some(format!("{} ignored: {why}", path.display()))),
            ),
        },
        Ok(None) => (Vec::new(), Origin::Empty(None)),
        Err(why) => (
            Vec::new(),
            Origin::Empty(Some(format!("{} ignored: {why}", path.display()))),
        ),
    }
}

impl PipelineCache {
    pub fn new(gpu: &GpuDevice) -> Result<PipelineCache, GpuError> {
        let key = DeviceKind::of(gpu);
        let (data, mut origin) = initial_data(&key);
        let info = vk::PipelineCacheCreateInfo::default().initial_data(&data);
        // SAFETY: valid create info on a valid device; the data's header matches this device.
        let made = unsafe { gpu.device.create_pipeline_cache(&info, None) };
        let (raw, loaded_bytes) = match made {
            Ok(raw) => (raw, data.len()),
            Err(_) => {
                // The driver refused the data: start empty.
                origin = Origin::Empty(Some("the driver refused the cached data".into()));
                let info = vk::PipelineCacheCreateInfo::default();
                // SAFETY: valid create info on a valid device.
                let raw = unsafe { gpu.device.create_pipeline_cache(&info, None) }
                    .vk("vkCreatePipelineCache")?;
                (raw, 0)
            }
        };
        Ok(PipelineCache {
            raw,
            key,
            origin,
            loaded_bytes,
        })
    }

    pub fn destroy(&mut self, device: &ash::Device) {
        // SAFETY: no pipeline creation uses the cache any more (the caller's contract).
        unsafe { device.destroy_pipeline_cache(self.raw, None) };
        self.raw = vk::PipelineCache::null();
    }
}

/// Keeps a cache's data for later sessions of this process and writes its file (atomically: a
/// reader sees the old file or the new one). Returns the bytes written.
pub fn save(
    device: &ash::Device,
    raw: vk::PipelineCache,
    key: &DeviceKind,
) -> Result<usize, String> {
    // SAFETY: the cache is valid; vkGetPipelineCacheData is internally synchronised.
    let data = unsafe { device.get_pipeline_cache_data(raw) }
        .map_err(|e| format!("vkGetPipelineCacheData failed: {e}"))?;
    if !written_for(key, &data) {
        return Err("the driver's cache data has an unexpected header".into());
    }
    in_memory().insert(*key, data.clone());
    let dir = directory().ok_or("neither XDG_CACHE_HOME nor HOME is set")?;
    let written = write_atomically(&dir, &file_name(key), &file_bytes(&data));
    if let Err(e) = &written {
        static SAID: std::sync::Once = std::sync::Once::new();
        SAID.call_once(|| eprintln!("contrastxr: pipeline cache not saved: {e}"));
    }
    written?;
    remove_old_foreign(&dir, &file_name(key));
    Ok(data.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key() -> DeviceKind {
        DeviceKind {
            vendor: 0x10005,
            device: 0,
            uuid: *b"0123456789abcdef",
        }
    }

    /// A driver header for `key` followed by a body.
    fn driver_data(key: &DeviceKind, body: &[u8]) -> Vec<u8> {
        let mut d = Vec::new();
        d.extend_from_slice(&(VK_HEADER as u32).to_le_bytes());
        d.extend_from_slice(&1u32.to_le_bytes());
        d.extend_from_slice(&key.vendor.to_le_bytes());
        d.extend_from_slice(&key.device.to_le_bytes());
        d.extend_from_slice(&key.uuid);
        d.extend_from_slice(body);
        d
    }

    #[test]
    fn a_whole_file_for_this_device_is_read_back() {
        let data = driver_data(&key(), b"pipelines");
        assert_eq!(parse_file(&file_bytes(&data), &key()), Ok(data));
    }

    #[test]
    fn damaged_truncated_and_foreign_files_are_refused() {
        let data = driver_data(&key(), b"pipelines");
        let whole = file_bytes(&data);
        let mut flipped = whole.clone();
        *flipped.last_mut().unwrap() ^= 1;
        let truncated = &whole[..whole.len() - 1];
        let mut other = key();
        other.uuid[0] ^= 1;
        let foreign = file_bytes(&driver_data(&other, b"pipelines"));
        let mut wrong_magic = whole.clone();
        wrong_magic[0] = b'X';
        for (bytes, says) in [
            (&flipped[..], "damaged"),
            (truncated, "damaged"),
            (&foreign[..], "another device"),
            (&wrong_magic[..], "not a contrastxr"),
            (&[][..], "not a contrastxr"),
        ] {
            let e = parse_file(bytes, &key()).unwrap_err();
            assert!(e.contains(says), "{e}");
        }
    }
}

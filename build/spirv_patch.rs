//! The SPIR-V 1.0 storage-buffer patch: naga's storage buffers rewritten into the form Vulkan
//! 1.0 takes without SPV_KHR_storage_buffer_storage_class.

const OP_EXTENSION: u32 = 10;
const OP_DECORATE: u32 = 71;
const OP_TYPE_POINTER: u32 = 32;
const OP_VARIABLE: u32 = 59;
const STORAGE_BUFFER: u32 = 12;
const UNIFORM: u32 = 2;
const BLOCK: u32 = 2;
const BUFFER_BLOCK: u32 = 3;

/// Rewrites naga's storage buffers into the SPIR-V 1.0 / Vulkan 1.0 form: `StorageBuffer`
/// storage class -> `Uniform`, their structs' `Block` -> `BufferBlock`, and the
/// SPV_KHR_storage_buffer_storage_class extension removed. Apps may create Vulkan 1.0 devices
/// without that extension (hello_xr does), and the layer must run on their device.
pub fn storage_buffers_to_vulkan10(words: Vec<u32>) -> Vec<u32> {
    let (header, body) = words.split_at(5);
    let mut insts: Vec<Vec<u32>> = Vec::new();
    let mut i = 0;
    while i < body.len() {
        let len = (body[i] >> 16) as usize;
        insts.push(body[i..i + len].to_vec());
        i += len;
    }
    let mut buffer_structs = std::collections::HashSet::new();
    for inst in insts.iter_mut() {
        let op = inst[0] & 0xffff;
        if op == OP_TYPE_POINTER && inst[2] == STORAGE_BUFFER {
            inst[2] = UNIFORM;
            buffer_structs.insert(inst[3]);
        } else if op == OP_VARIABLE && inst[3] == STORAGE_BUFFER {
            inst[3] = UNIFORM;
        }
    }
    let is_extension = |inst: &Vec<u32>| {
        inst[0] & 0xffff == OP_EXTENSION
            && inst[1..]
                .iter()
                .flat_map(|w| w.to_le_bytes())
                .take_while(|&b| b != 0)
                .collect::<Vec<u8>>()
                == b"SPV_KHR_storage_buffer_storage_class"
    };
    insts.retain(|inst| !is_extension(inst));
    for inst in insts.iter_mut() {
        if inst[0] & 0xffff == OP_DECORATE && inst[2] == BLOCK && buffer_structs.contains(&inst[1])
        {
            inst[2] = BUFFER_BLOCK;
        }
    }
    header
        .iter()
        .copied()
        .chain(insts.into_iter().flatten())
        .collect()
}

//! `--check-untouched`'s bookkeeping, whatever the graphics API: which frame last wrote each
//! image of a swapchain, and the frames whose image had changed when it came back.

pub struct Untouched {
    /// Per swapchain image: the frame that last wrote it, if any.
    written: Vec<Option<u32>>,
    /// Images compared with what they were released with.
    pub checked: u32,
    /// The frames whose image had changed when it was acquired again.
    pub modified: Vec<u32>,
}

impl Untouched {
    pub fn new(images: usize) -> Untouched {
        Untouched {
            written: vec![None; images],
            checked: 0,
            modified: Vec::new(),
        }
    }

    /// Whether image `index` was written before (so what it holds now is to be compared).
    pub fn written_before(&self, index: u32) -> bool {
        self.written[index as usize].is_some()
    }

    /// Image `index`, just written by `frame`; `same`: whether it still held what the client
    /// had written before (None when it was not read back).
    pub fn record(&mut self, index: u32, frame: u32, same: Option<bool>) {
        if let (Some(previous), Some(same)) = (self.written[index as usize], same) {
            self.checked += 1;
            if !same && !self.modified.contains(&previous) {
                self.modified.push(previous);
            }
        }
        self.written[index as usize] = Some(frame);
    }
}

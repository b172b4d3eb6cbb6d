//! A bounds-checked reader of the primitive fields of ROS messages, in
//! ROS 1's packed layout or ROS 2's CDR (aligned, either byte order).

/// A bounds-checked reader of primitive values.
pub(crate) struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
    /// Where alignment is counted from (the end of CDR's encapsulation header).
    base: usize,
    little: bool,
    /// CDR aligns each primitive to its size; ROS 1 packs.
    align: bool,
    /// ROS 1's `Header` starts with a `seq`.
    ros1: bool,
}

impl<'a> Cursor<'a> {
    /// A reader of a CDR message after its 4-byte encapsulation header
    /// (byte 1: 0 or 2 big-endian, 1 or 3 little-endian).
    pub(crate) fn cdr(data: &'a [u8]) -> Result<Self, String> {
        if data.len() < 4 {
            return Err("shorter than the CDR encapsulation header".into());
        }
        let little = match data[1] {
            0 | 2 => false,
            1 | 3 => true,
            k => return Err(format!("unknown CDR encapsulation kind {k}")),
        };
        Ok(Cursor { data, pos: 4, base: 4, little, align: true, ros1: false })
    }

    /// A reader of a ROS 1 message (packed, little-endian).
    pub(crate) fn ros1(data: &'a [u8]) -> Self {
        Cursor { data, pos: 0, base: 0, little: true, align: false, ros1: true }
    }

    pub(crate) fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        if self.align && n > 1 {
            let off = (self.pos - self.base) % n;
            if off != 0 {
                self.pos += n - off;
            }
        }
        let end = self.pos.checked_add(n).filter(|e| *e <= self.data.len());
        let Some(end) = end else {
            return Err(format!("truncated at byte {} reading {what}", self.pos));
        };
        let s = &self.data[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    /// A `std_msgs/Header`: its stamp, seconds, and its `frame_id` without a
    /// leading `/` (ROS 1's `seq` skipped; ROS 2's `sec` is signed).
    pub(crate) fn header(&mut self) -> Result<(f64, String), String> {
        if self.ros1 {
            self.u32("header.seq")?;
        }
        let sec = self.u32("header.stamp.sec")?;
        let sec = if self.ros1 { f64::from(sec) } else { f64::from(sec as i32) };
        let nanosec = self.u32("header.stamp.nanosec")?;
        let frame = self.string("header.frame_id")?;
        Ok((sec + f64::from(nanosec) * 1e-9, frame.trim_start_matches('/').to_string()))
    }

    /// Bytes left after the cursor.
    pub(crate) fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }

    pub(crate) fn u32(&mut self, what: &str) -> Result<u32, String> {
        let b: [u8; 4] = self.take(4, what)?.try_into().map_err(|_| what.to_string())?;
        Ok(if self.little { u32::from_le_bytes(b) } else { u32::from_be_bytes(b) })
    }

    pub(crate) fn f32(&mut self, what: &str) -> Result<f32, String> {
        Ok(f32::from_bits(self.u32(what)?))
    }

    pub(crate) fn f64(&mut self, what: &str) -> Result<f64, String> {
        let b: [u8; 8] = self.take(8, what)?.try_into().map_err(|_| what.to_string())?;
        Ok(f64::from_bits(if self.little { u64::from_le_bytes(b) } else { u64::from_be_bytes(b) }))
    }

    pub(crate) fn string(&mut self, what: &str) -> Result<String, String> {
        let len = self.u32(what)? as usize;
        let bytes = self.take_bytes(len, what)?;
        Ok(String::from_utf8_lossy(bytes).trim_end_matches('\0').to_string())
    }

    pub(crate) fn take_bytes(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let align = std::mem::replace(&mut self.align, false);
        let r = self.take(n, what);
        self.align = align;
        r
    }

    pub(crate) fn f32_seq(&mut self, what: &str) -> Result<Vec<f32>, String> {
        let n = self.u32(what)? as usize;
        if n.saturating_mul(4) > self.data.len().saturating_sub(self.pos) + 4 {
            return Err(format!("{what}: {n} values do not fit in the message"));
        }
        (0..n).map(|_| self.f32(what)).collect()
    }
}

//! Consistent Overhead Byte Stuffing (Cheshire & Baker, 1999): removes every `0x00` from a frame so `0x00` can
//! delimit frames. Output is at most `n + n / 254 + 1` bytes for `n` input bytes.

/// Why a COBS block sequence could not be decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CobsError {
    /// A block's code byte claims more bytes than remain (the frame was cut short).
    Truncated,
    /// A `0x00` byte inside the encoded data (only possible if the caller did not split on delimiters).
    ZeroByte,
    /// The output buffer is too small.
    OutputFull,
}

/// Largest encoding of `n` bytes (without the delimiter).
pub const fn max_encoded_len(n: usize) -> usize {
    n + n / 254 + 1
}

/// Encodes `input` into `out` (no delimiter); returns the encoded length, or `None` when `out` is too small.
pub fn encode(input: &[u8], out: &mut [u8]) -> Option<usize> {
    let mut code_at = 0usize;
    let mut w = 1usize;
    let mut code: u8 = 1;
    for &b in input {
        if b == 0 {
            *out.get_mut(code_at)? = code;
            code_at = w;
            w += 1;
            code = 1;
        } else {
            *out.get_mut(w)? = b;
            w += 1;
            code += 1;
            if code == 0xFF {
                *out.get_mut(code_at)? = code;
                code_at = w;
                w += 1;
                code = 1;
            }
        }
    }
    *out.get_mut(code_at)? = code;
    Some(w)
}

/// Decodes one frame's blocks (`input` excludes the delimiter) into `out`; returns the decoded length.
pub fn decode(input: &[u8], out: &mut [u8]) -> Result<usize, CobsError> {
    let mut rest = input;
    let mut w = 0usize;
    // Each iteration consumes at least one byte of `input`: bounded by `input.len()`.
    while let Some((&code, tail)) = rest.split_first() {
        if code == 0 {
            return Err(CobsError::ZeroByte);
        }
        let n = usize::from(code - 1);
        let (block, after) = tail.split_at_checked(n).ok_or(CobsError::Truncated)?;
        if block.contains(&0) {
            return Err(CobsError::ZeroByte);
        }
        out.get_mut(w..w + n)
            .ok_or(CobsError::OutputFull)?
            .copy_from_slice(block);
        w += n;
        rest = after;
        if code != 0xFF && !rest.is_empty() {
            *out.get_mut(w).ok_or(CobsError::OutputFull)? = 0;
            w += 1;
        }
    }
    Ok(w)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn roundtrip(data: &[u8]) {
        let mut enc = [0u8; 1200];
        let n = encode(data, &mut enc).unwrap();
        assert!(n <= max_encoded_len(data.len()));
        assert!(!enc[..n].contains(&0));
        let mut dec = [0u8; 1200];
        let m = decode(&enc[..n], &mut dec).unwrap();
        assert_eq!(&dec[..m], data);
    }

    #[test]
    fn known_vectors() {
        // Vectors from the COBS paper / Wikipedia table.
        let mut out = [0u8; 16];
        assert_eq!(encode(&[0x00], &mut out), Some(2));
        assert_eq!(&out[..2], &[0x01, 0x01]);
        assert_eq!(encode(&[0x11, 0x22, 0x00, 0x33], &mut out), Some(5));
        assert_eq!(&out[..5], &[0x03, 0x11, 0x22, 0x02, 0x33]);
        assert_eq!(encode(&[0x11, 0x00, 0x00, 0x00], &mut out), Some(5));
        assert_eq!(&out[..5], &[0x02, 0x11, 0x01, 0x01, 0x01]);
    }

    #[test]
    fn roundtrips_including_long_runs() {
        roundtrip(&[]);
        roundtrip(&[0]);
        roundtrip(&[1; 253]);
        roundtrip(&[1; 254]);
        roundtrip(&[1; 255]);
        roundtrip(&[7; 1000]);
        let mixed: std::vec::Vec<u8> = (0..1000u32).map(|i| (i % 7) as u8).collect();
        roundtrip(&mixed);
    }

    #[test]
    fn truncated_block_is_reported() {
        let mut out = [0u8; 16];
        assert_eq!(decode(&[0x05, 1, 2], &mut out), Err(CobsError::Truncated));
        assert_eq!(decode(&[0x02, 0], &mut out), Err(CobsError::ZeroByte));
    }
}

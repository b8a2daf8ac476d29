//! The digest of a frame's 8-bit display output: what approved frames are kept and matched by
//! (`results/README.md`, "Frame digests"). One definition, so that the harness that writes it and
//! the dashboard or a runner that checks it cannot disagree.
//!
//! SHA-256 (the `sha2` crate, RustCrypto), because it is the content digest the dashboard
//! already keeps its blobs and tokens by (one hash in the project), any tool can recompute it
//! (`sha256sum` over the bytes below), and with the SHA extensions of current x86 and ARM CPUs
//! (detected at run time by `sha2`) it hashes well over 1 GB/s: far less than the readback of
//! the frame it digests.

use sha2::{Digest, Sha256};

/// Lowercase hex SHA-256 of: the width and the height as little-endian `u32`, then the pixels'
/// 8-bit sRGB R, G, B bytes, row by row from the top (no padding, no alpha).
pub fn frame_digest(width: u32, height: u32, rgb: &[u8]) -> String {
    let mut h = Sha256::new();
    h.update(width.to_le_bytes());
    h.update(height.to_le_bytes());
    h.update(rgb);
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn digest_covers_size_and_every_byte() {
        let a = frame_digest(2, 1, &[0, 0, 0, 255, 255, 255]);
        assert_eq!(a.len(), 64);
        assert_ne!(a, frame_digest(1, 2, &[0, 0, 0, 255, 255, 255]));
        assert_ne!(a, frame_digest(2, 1, &[0, 0, 0, 255, 255, 254]));
        // The documented bytes, hashed by hand: 02 00 00 00 01 00 00 00 then the pixels.
        let mut bytes = vec![2, 0, 0, 0, 1, 0, 0, 0];
        bytes.extend([0, 0, 0, 255, 255, 255]);
        let by_hand: String = Sha256::digest(&bytes)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        assert_eq!(a, by_hand);
    }
}

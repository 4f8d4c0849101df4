//! MERL `.binary` tables: any bytes give a table or an error, never a panic.
//!
//! A valid file has exactly 34,992,012 bytes, so raw fuzz inputs only reach the header and size
//! checks. Inputs whose first byte is odd are therefore expanded into a full-size file: the
//! remaining bytes give the 12-byte header and are repeated as the values, which exercises the
//! value validation (NaN/Inf/negative) and the lookups on accepted tables.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lustre_brdf::measured::merl::{MerlTable, NegativeValues, FILE_BYTES};

fuzz_target!(|data: &[u8]| {
    let expanded;
    let bytes = match data.split_first() {
        Some((flag, rest)) if flag & 1 == 1 && rest.len() >= 20 => {
            let mut buf = Vec::with_capacity(FILE_BYTES);
            buf.extend_from_slice(&[90, 0, 0, 0, 90, 0, 0, 0, 180, 0, 0, 0]);
            if rest[0] & 1 == 1 {
                buf[..12].copy_from_slice(&rest[..12]);
            }
            let body = &rest[12..];
            while buf.len() < FILE_BYTES {
                let n = body.len().min(FILE_BYTES - buf.len());
                buf.extend_from_slice(&body[..n]);
            }
            expanded = buf;
            &expanded[..]
        }
        _ => data,
    };
    for policy in [NegativeValues::Reject, NegativeValues::Missing] {
        if let Ok(t) = MerlTable::parse_with("<fuzz>", bytes, policy) {
            let _ = t.lookup_trilinear(0.1, 0.2, 0.3);
            let _ = t.lookup_nearest(1.5, 1.5, -0.3);
        }
    }
});

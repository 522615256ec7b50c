//! Arbitrary bytes through the whole front end, exactly as `lagc check`
//! runs it: UTF-8 decoding, parsing, checking, rendering. Any panic or
//! stack overflow is a bug.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    lagc::on_big_stack(|| {
        let (source, result) = lagc::frontend_bytes(bytes);
        if let Err(diagnostics) = result {
            assert!(!diagnostics.is_empty());
            lagc::diagnostic::render(&diagnostics, "fuzz.lag", &source, false);
        }
    });
});

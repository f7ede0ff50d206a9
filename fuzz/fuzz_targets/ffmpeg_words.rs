//! `--print-ffmpeg`: an output pattern and a video name (the input's two lines), quoted into
//! the printed command, come back word for word from a shell lexer.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        rayreel::fuzzing::ffmpeg_words(text);
    }
});

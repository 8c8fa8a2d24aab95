//! Reading files and parsing single values, shared by the CSV and TOML readers.

use std::io;
use std::path::Path;

use super::error::DatasetError;

/// The largest dataset file read [bytes] (1 GiB: far more than the 100 000 captures a
/// dataset may have, with all their vertices).
pub(crate) const MAX_FILE_BYTES: u64 = 1 << 30;

/// What kind of thing `meta` describes, for a message refusing it.
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_socket() {
            return "a socket";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
    }
    "not a regular file"
}

/// Opens `path` for reading without ever blocking on it: a FIFO or device is refused
/// (checked on the opened handle, so it cannot be swapped in between), and so is a file
/// larger than `limit` bytes. Returns the file and its size.
pub(crate) fn open_regular(path: &Path, limit: u64) -> Result<(std::fs::File, u64), io::Error> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // Opening a FIFO for reading blocks until a writer appears; non-blocking, it
        // returns at once and is then refused below.
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("it is {}; expected a regular file", kind_of(&meta)),
        ));
    }
    if meta.len() > limit {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "it is {} bytes, more than the {limit} bytes a file may have here",
                meta.len()
            ),
        ));
    }
    Ok((file, meta.len()))
}

/// Reads a whole file. `Ok(None)` when it does not exist and is optional; an error when it
/// does not exist and is `required`, is not a regular file (a FIFO, a device, a
/// directory), is larger than [`MAX_FILE_BYTES`], cannot be read, or holds only white
/// space.
pub(crate) fn read_file(
    path: &Path,
    required: bool,
    empty_hint: &str,
) -> Result<Option<Vec<u8>>, DatasetError> {
    let read = open_regular(path, MAX_FILE_BYTES).and_then(|(file, len)| {
        use std::io::Read as _;
        let mut bytes = Vec::with_capacity(len as usize);
        // Bounded even if the file grows while it is read.
        file.take(MAX_FILE_BYTES + 1).read_to_end(&mut bytes)?;
        if bytes.len() as u64 > MAX_FILE_BYTES {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("it grew past {MAX_FILE_BYTES} bytes while being read"),
            ));
        }
        Ok(bytes)
    });
    let bytes = match read {
        Ok(bytes) => bytes,
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            if !required {
                return Ok(None);
            }
            let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
            let name = path.file_name().and_then(|n| n.to_str());
            let hint = match dir {
                Some(dir) if !dir.is_dir() => {
                    format!(" (the directory {} does not exist)", dir.display())
                }
                _ if matches!(name, Some(super::DATASET_TOML | super::CAPTURES_CSV)) => {
                    " (a dataset directory needs dataset.toml and captures.csv)".to_string()
                }
                _ => String::new(),
            };
            return Err(DatasetError::NotFound {
                path: path.to_path_buf(),
                hint,
            });
        }
        Err(e) => return Err(DatasetError::io(path, "read", e)),
    };
    let content = bytes
        .strip_prefix(b"\xEF\xBB\xBF".as_slice())
        .unwrap_or(&bytes);
    if content.iter().all(u8::is_ascii_whitespace) {
        return Err(DatasetError::Empty {
            path: path.to_path_buf(),
            hint: empty_hint.to_string(),
        });
    }
    Ok(Some(bytes))
}

/// The 1-based line of byte `offset` in `text`.
pub(crate) fn line_at(text: &[u8], offset: usize) -> u64 {
    let end = offset.min(text.len());
    1 + text[..end].iter().filter(|&&b| b == b'\n').count() as u64
}

/// Parses a finite number.
pub(crate) fn parse_f64(s: &str) -> Result<f64, String> {
    if s.is_empty() {
        return Err("missing value, expected a number".into());
    }
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(_) => Err(format!("'{s}' is not a finite number")),
        Err(_) => Err(format!("'{s}' is not a number")),
    }
}

/// Parses a non-negative integer that fits `T`.
pub(crate) fn parse_uint<T: TryFrom<u64>>(s: &str) -> Result<T, String> {
    if s.is_empty() {
        return Err("missing value, expected a non-negative integer".into());
    }
    match s.parse::<u64>() {
        Ok(n) => T::try_from(n).map_err(|_| format!("{n} is too large")),
        Err(_) if s.parse::<i64>().is_ok_and(|n| n < 0) => {
            Err(format!("must not be negative, got {s}"))
        }
        Err(_) => Err(format!("'{s}' is not a non-negative integer")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers() {
        assert_eq!(parse_f64("-0.25"), Ok(-0.25));
        assert_eq!(parse_f64("1e-3"), Ok(1e-3));
        assert_eq!(parse_f64("abc").unwrap_err(), "'abc' is not a number");
        assert_eq!(
            parse_f64("NaN").unwrap_err(),
            "'NaN' is not a finite number"
        );
        assert_eq!(
            parse_f64("-inf").unwrap_err(),
            "'-inf' is not a finite number"
        );
        assert!(parse_f64("").unwrap_err().contains("missing value"));
        assert_eq!(parse_f64("-0").map(f64::to_bits), Ok((-0.0f64).to_bits()));
    }

    #[test]
    fn unsigned() {
        assert_eq!(parse_uint::<u64>("17"), Ok(17));
        assert_eq!(
            parse_uint::<u64>("-3").unwrap_err(),
            "must not be negative, got -3"
        );
        assert_eq!(
            parse_uint::<u64>("3.0").unwrap_err(),
            "'3.0' is not a non-negative integer"
        );
        assert_eq!(
            parse_uint::<u32>("4294967296").unwrap_err(),
            "4294967296 is too large"
        );
        assert!(parse_uint::<u32>("").unwrap_err().contains("missing value"));
    }

    #[test]
    fn lines() {
        let text = b"a\nb\r\nc";
        assert_eq!(line_at(text, 0), 1);
        assert_eq!(line_at(text, 2), 2);
        assert_eq!(line_at(text, 5), 3);
        assert_eq!(line_at(text, 100), 3);
    }

    #[test]
    fn missing_and_empty_files() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.csv");
        assert!(read_file(&path, false, "").unwrap().is_none());
        let e = read_file(&path, true, "").unwrap_err();
        assert!(matches!(e, DatasetError::NotFound { .. }), "{e}");
        let e = read_file(&dir.path().join("nope/x.csv"), true, "").unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
        std::fs::write(&path, " \n\r\n").unwrap();
        let e = read_file(&path, false, " (hint)").unwrap_err();
        assert!(e.to_string().ends_with("the file is empty (hint)"), "{e}");
        std::fs::write(&path, "a").unwrap();
        assert_eq!(read_file(&path, true, "").unwrap().unwrap(), b"a");
    }
}

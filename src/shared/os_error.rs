//! An operating system error said in the user's terms, for the error
//! messages ([`super::exit`]) and a stdout that cannot be written
//! ([`super::out`]).

/// An operating system error in the user's terms: what it means for a file
/// or a port, without the `(os error N)` of the C library's wording.
pub fn os_text(err: &std::io::Error) -> String {
    const EIO: i32 = 5;
    const ENXIO: i32 = 6;
    const ENOTDIR: i32 = 20;
    const EISDIR: i32 = 21;
    const ENOTTY: i32 = 25;
    const ENOSPC: i32 = 28;
    const EROFS: i32 = 30;
    let said = match err.raw_os_error() {
        Some(ENOTTY) => "not a serial port",
        Some(EISDIR) => "it is a directory",
        Some(ENOTDIR) => "a part of the path is not a directory",
        Some(EIO) | Some(ENXIO) => "the device is gone (unplugged, or its program ended)",
        Some(ENOSPC) => "the disk is full",
        Some(EROFS) => "the file system is read-only",
        _ => match err.kind() {
            std::io::ErrorKind::NotFound => "no such file or directory",
            std::io::ErrorKind::PermissionDenied => "permission denied",
            std::io::ErrorKind::AlreadyExists => "a file of that name exists",
            _ => "",
        },
    };
    if !said.is_empty() {
        return said.to_owned();
    }
    let text = err.to_string();
    match text.find(" (os error ") {
        Some(at) => text[..at].to_owned(),
        None => text,
    }
}

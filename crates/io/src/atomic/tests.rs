use super::*;

/// A new empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("servobus-io-atomic-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).expect("a scratch directory");
    dir
}

/// A new directory for one test, with the file `file` in it holding `old`:
/// the directory and the file's path.
fn with_old_file(test: &str, file: &str, old: &str) -> (PathBuf, PathBuf) {
    let dir = scratch(test);
    let path = dir.join(file);
    fs::write(&path, old).expect("old file");
    (dir, path)
}

/// The text of the file at `path`.
fn text(path: &Path) -> String {
    fs::read_to_string(path).expect("read")
}

/// An atomic file for `path` with `bytes` written, not committed yet.
fn written(path: &Path, bytes: &[u8]) -> AtomicFile {
    let mut file = AtomicFile::create(path).expect("created");
    file.write_all(bytes).expect("written");
    file
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .expect("the directory lists")
        .map(|e| {
            e.expect("an entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    names.sort();
    names
}

#[test]
fn commit_replaces_the_file_and_leaves_no_temporary() {
    let (dir, path) = with_old_file("commit", "log.csv", "yesterday");
    let file = written(&path, b"today");
    // Until the commit the old file is all there is at the target.
    assert_eq!(text(&path), "yesterday");
    assert_eq!(names(&dir).len(), 2, "{:?}", names(&dir));
    file.commit().expect("committed");
    assert_eq!(text(&path), "today");
    assert_eq!(names(&dir), ["log.csv"]);
}

#[test]
fn the_temporary_is_named_after_the_target_beside_it() {
    let dir = scratch("name");
    let path = dir.join("plot.svg");
    let file = AtomicFile::create(&path).expect("created");
    let pid = std::process::id();
    assert_eq!(names(&dir), [format!(".plot.svg.{pid}.tmp")]);
    drop(file);
}

#[test]
fn drop_without_commit_leaves_the_old_file_and_removes_the_temporary() {
    let (dir, path) = with_old_file("drop", "arm.calibration.yaml", "kept");
    let file = written(&path, b"half a calibra");
    drop(file);
    assert_eq!(text(&path), "kept");
    assert_eq!(names(&dir), ["arm.calibration.yaml"]);
}

#[test]
fn a_new_file_appears_only_on_commit() {
    let dir = scratch("new");
    let path = dir.join("motion.yaml");
    let file = written(&path, b"keyframes: []\n");
    assert!(!path.exists());
    file.commit().expect("committed");
    assert_eq!(text(&path), "keyframes: []\n");

    let other = dir.join("other.yaml");
    drop(AtomicFile::create(&other).expect("created"));
    assert_eq!(names(&dir), ["motion.yaml"]);
}

#[test]
fn write_atomic_writes_the_bytes() {
    let (dir, path) = with_old_file("write", "robot.yaml", "a longer old text");
    write_atomic(&path, b"short").expect("written");
    assert_eq!(text(&path), "short");
    assert_eq!(names(&dir), ["robot.yaml"]);
}

#[test]
fn a_missing_directory_is_refused_naming_the_file() {
    let dir = scratch("missing");
    let path = dir.join("nowhere").join("log.csv");
    let err = write_atomic(&path, b"x").expect_err("refused");
    assert!(matches!(err, OutputError::NoDirectory { .. }), "{err:?}");
    assert_eq!(err.path(), path.as_path());
    assert!(err.to_string().contains("log.csv"), "{err}");
    assert!(check_output(&path).is_err());
    assert!(names(&dir).is_empty());
}

#[test]
fn a_directory_is_not_a_target() {
    let dir = scratch("dir");
    let err = AtomicFile::create(&dir).expect_err("refused");
    assert!(matches!(err, OutputError::IsDirectory(_)), "{err:?}");
    assert!(matches!(
        check_output(&dir),
        Err(OutputError::IsDirectory(_))
    ));
}

#[test]
fn a_read_only_file_is_not_replaced() {
    let (dir, path) = with_old_file("readonly", "cal.yaml", "kept");
    let mut perms = fs::metadata(&path).expect("metadata").permissions();
    perms.set_readonly(true);
    fs::set_permissions(&path, perms).expect("read-only");
    let err = write_atomic(&path, b"new").expect_err("refused");
    assert!(matches!(err, OutputError::ReadOnly(_)), "{err:?}");
    assert!(check_output(&path).is_err());
    assert_eq!(text(&path), "kept");
    assert_eq!(names(&dir), ["cal.yaml"]);
}

#[test]
fn check_output_creates_and_changes_nothing() {
    let dir = scratch("check");
    let new = dir.join("new.csv");
    let old = dir.join("old.csv");
    fs::write(&old, "612 KB of yesterday").expect("old file");
    check_output(&new).expect("writable");
    check_output(&old).expect("writable");
    assert_eq!(names(&dir), ["old.csv"]);
    assert_eq!(text(&old), "612 KB of yesterday");
}

#[cfg(unix)]
#[test]
fn a_replaced_file_keeps_its_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let (_, path) = with_old_file("mode", "cal.yaml", "old");
    fs::set_permissions(&path, Permissions::from_mode(0o640)).expect("mode");
    write_atomic(&path, b"new").expect("written");
    let mode = fs::metadata(&path).expect("metadata").permissions().mode();
    assert_eq!(mode & 0o777, 0o640);
}

#[cfg(unix)]
#[test]
fn a_symbolic_link_stays_a_link_to_the_new_file() {
    let dir = scratch("link");
    let real = dir.join("real.csv");
    let link = dir.join("link.csv");
    fs::write(&real, "old").expect("old file");
    std::os::unix::fs::symlink(&real, &link).expect("link");
    write_atomic(&link, b"new").expect("written");
    assert!(fs::symlink_metadata(&link)
        .expect("metadata")
        .file_type()
        .is_symlink());
    assert_eq!(text(&real), "new");
    assert_eq!(names(&dir), ["link.csv", "real.csv"]);
}

#[cfg(target_os = "linux")]
#[test]
fn a_device_is_written_in_place_and_its_errors_name_it() {
    let null = AtomicFile::create("/dev/null").expect("opened");
    assert!(null.is_direct());
    null.commit().expect("nothing to rename");

    check_output("/dev/full").expect("a device is not opened by the check");
    let err = write_atomic("/dev/full", b"a report").expect_err("the device is full");
    assert!(matches!(err, OutputError::Write { .. }), "{err:?}");
    let text = err.to_string();
    assert!(text.starts_with("cannot write /dev/full: "), "{text}");

    // Through `Write`, the I/O error says the file too.
    let mut full = AtomicFile::create("/dev/full").expect("opened");
    let err = full.write_all(b"row\n").expect_err("the device is full");
    assert!(
        err.to_string().starts_with("cannot write /dev/full: "),
        "{err}"
    );
}

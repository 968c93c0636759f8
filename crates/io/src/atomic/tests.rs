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

/// The pid of a process that has ended (a child that ran and was waited for).
fn dead_pid() -> u32 {
    let mut child = std::process::Command::new("true")
        .spawn()
        .expect("`true` runs");
    let pid = child.id();
    child.wait().expect("it ends");
    pid
}

#[test]
fn temporaries_of_killed_runs_of_the_target_are_removed_by_the_next_write() {
    if !Path::new("/proc/self").exists() {
        return; // nothing can tell a dead process from a live one here
    }
    let (dir, path) = with_old_file("stale", "log.csv", "old");
    let dead = dead_pid();
    let left = [
        format!(".log.csv.{dead}.tmp"),
        format!(".log.csv.{dead}.3.tmp"),
    ];
    // Kept: a live process's (pid 1 always runs), another target's, and
    // names that only look alike.
    let kept = [
        ".log.csv.1.tmp".to_owned(),
        format!(".other.csv.{dead}.tmp"),
        ".log.csv.abc.tmp".to_owned(),
        format!(".log.csv.{dead}.x.tmp"),
        format!("log.csv.{dead}.tmp"),
    ];
    for name in left.iter().chain(&kept) {
        fs::write(dir.join(name), "partial").expect("a leftover");
    }
    write_atomic(&path, b"new").expect("written");
    assert_eq!(text(&path), "new");
    let mut expected: Vec<String> = kept.to_vec();
    expected.push("log.csv".to_owned());
    expected.sort();
    assert_eq!(names(&dir), expected);
}

#[test]
fn a_long_legal_name_gets_a_legal_unique_temporary() {
    let dir = scratch("long");
    // 255 bytes: the longest legal name; two that differ only at the end.
    let a = format!("{}a.csv", "x".repeat(250));
    let b = format!("{}b.csv", "x".repeat(250));
    assert_eq!(a.len(), 255);
    let (pa, pb) = (dir.join(&a), dir.join(&b));
    let fa = written(&pa, b"first");
    let fb = written(&pb, b"second");
    let temps = names(&dir);
    assert_eq!(temps.len(), 2, "{temps:?}");
    assert!(temps.iter().all(|t| t.len() <= 255), "{temps:?}");
    assert_ne!(temps[0], temps[1]);
    fa.commit().expect("the first commits");
    fb.commit().expect("the second commits");
    assert_eq!(text(&pa), "first");
    assert_eq!(text(&pb), "second");
    assert_eq!(names(&dir).len(), 2);
    // A multi-byte character at the cut is not split.
    let c = format!("{}.csv", "é".repeat(125));
    assert_eq!(c.len(), 254);
    write_atomic(dir.join(&c), b"third").expect("written");
    assert_eq!(text(&dir.join(&c)), "third");
    // A killed run's temporary of a long name is found and removed too.
    if Path::new("/proc/self").exists() {
        let stale = format!("{}.{}.tmp", temp::base(&a), dead_pid());
        assert!(stale.len() <= 255, "{}", stale.len());
        fs::write(dir.join(&stale), "partial").expect("a leftover");
        write_atomic(&pa, b"again").expect("written");
        assert!(!names(&dir).contains(&stale), "{:?}", names(&dir));
    }
}

#[test]
fn temporary_names_are_parsed_back_to_their_process() {
    assert_eq!(temp::base("log.csv"), ".log.csv");
    assert_eq!(temp::owner(".log.csv.123.tmp", ".log.csv"), Some(123));
    assert_eq!(temp::owner(".log.csv.123.7.tmp", ".log.csv"), Some(123));
    for other in [
        ".log.csv.tmp",
        ".log.csv..tmp",
        ".log.csv.12a.tmp",
        ".log.csv.1.2.3.tmp",
        ".log.csv.123",
        ".log.csvx.123.tmp",
        ".log.csv.99999999999.tmp",
    ] {
        assert_eq!(temp::owner(other, ".log.csv"), None, "{other}");
    }
    let long = "y".repeat(240);
    let base = temp::base(&long);
    assert!(base.len() + 26 <= temp::NAME_MAX, "{}", base.len());
    assert_ne!(base, temp::base(&"y".repeat(241)));
}

use super::*;

#[test]
fn devices_directories_and_large_files_are_refused_by_name() {
    let dir = tempfile::tempdir().expect("temp dir");
    let small = dir.path().join("a.txt");
    std::fs::write(&small, "hello").expect("writable");
    assert_eq!(read_to_string_bounded(&small, 5).expect("fits"), "hello");
    assert!(matches!(
        read_to_string_bounded(&small, 4),
        Err(OpenError::TooLarge {
            bytes: 5,
            max: 4,
            ..
        })
    ));
    assert!(matches!(
        open_bounded(dir.path(), 1 << 20),
        Err(OpenError::NotAFile {
            kind: "directory",
            ..
        })
    ));
    #[cfg(unix)]
    {
        let link = dir.path().join("zero.trc");
        std::os::unix::fs::symlink("/dev/zero", &link).expect("symlink");
        let e = open_bounded(&link, 1 << 20).expect_err("a device");
        assert!(e.to_string().contains("character device"), "{e}");
    }
}

use super::*;

#[test]
fn an_input_is_never_the_output_and_existing_files_need_force() {
    let dir = tempfile::tempdir().expect("temp dir");
    let take = dir.path().join("take.trc");
    std::fs::write(&take, "x").expect("writable");
    let e = check_out(&take, &[&take], true).expect_err("its own input");
    assert!(e.to_string().contains("also an input"), "{e}");
    let same = dir.path().join(".").join("take.trc");
    assert!(
        check_out(&same, &[&take], true).is_err(),
        "the same file by another path"
    );
    let e = check_out(&take, &[], false).expect_err("exists");
    assert!(e.to_string().contains("--force"), "{e}");
    assert!(check_out(&take, &[], true).is_ok());
    assert!(check_out(&dir.path().join("new.trc"), &[&take], false).is_ok());
    assert!(check_out_format(Path::new("m.json"), "json").is_ok());
    assert!(check_out_format(Path::new("m.model"), "json").is_ok());
    assert!(check_out_format(Path::new("u.CSV"), "csv").is_ok());
    let e = check_out_format(Path::new("u.c3d"), "csv").expect_err("a take format");
    assert!(e.to_string().contains("name the output .csv"), "{e}");
    assert!(check_out_format(Path::new("m.trc"), "json").is_err());
    assert!(check_out_format(Path::new("m.csv"), "json").is_err());
    let e = check_out(dir.path(), &[&take], true).expect_err("a folder");
    assert!(e.to_string().contains("is a folder"), "{e}");
}

use super::*;

/// A reader that went away.
struct Closed;

impl std::io::Write for Closed {
    fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
        Err(std::io::ErrorKind::BrokenPipe.into())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[test]
fn a_closed_stdout_is_not_a_failure_through_serde_json_too() {
    use std::io::Write as _;
    let plain = Closed.write_all(b"x").map_err(anyhow::Error::from);
    assert!(is_broken_pipe(&plain.expect_err("closed")));
    // What `inspect --json | head -1` returned: the model's error around serde_json's.
    let json = serde_json::to_writer(Closed, &[1.0; 4]).expect_err("closed");
    let err = anyhow::Error::from(ica_core::model::ModelError::Write(json));
    assert!(is_broken_pipe(&err), "{err:#}");
    let full = std::io::Error::from(std::io::ErrorKind::StorageFull);
    let json = serde_json::Error::io(full);
    assert!(
        !is_broken_pipe(&anyhow::Error::from(json)),
        "another write error stays an error"
    );
}

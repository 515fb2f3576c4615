use super::*;

#[test]
fn a_sweep_ramps_to_each_target_in_turn_one_share_each() {
    let targets = ["sad", "happy", "angry"].map(String::from);
    let cues = sweep(&targets, Duration::from_secs(4));
    let at: Vec<u64> = cues.iter().map(|c| c.at.as_secs()).collect();
    assert_eq!(at, [0, 0, 0, 4, 8]);
    assert_eq!(cues[0].control, Control::Ramp(4.0));
    assert_eq!(cues[1].control, Control::Target("sad".into()));
    assert_eq!(cues[2].control, Control::Amount(1.0));
    assert_eq!(cues[4].control, Control::Target("angry".into()));
    assert!(sweep(&[], Duration::from_secs(4)).is_empty());
}

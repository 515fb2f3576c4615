use super::*;

#[test]
fn ids_round_trip_and_sizes_are_checked() {
    for id in 0..=u16::MAX {
        if let Some(m) = MessageId::from_u16(id) {
            assert_eq!(m.as_u16(), id);
        }
    }
    assert_eq!(check_packet(&[4, 0, 0, 0]), Ok(MessageId::RequestModelDef));
    assert_eq!(
        check_packet(&[4, 0, 1, 0]),
        Err(NatNetError::PayloadSize {
            declared: 1,
            actual: 0
        })
    );
    assert_eq!(
        check_packet(&[4, 0, 0, 0, 9]),
        Err(NatNetError::PayloadSize {
            declared: 0,
            actual: 1
        })
    );
    assert_eq!(
        check_packet(&[0, 1, 0, 0]),
        Err(NatNetError::UnknownMessage { id: 256 })
    );
    assert_eq!(
        check_packet(&[7]),
        Err(NatNetError::Truncated { offset: 1 })
    );
}

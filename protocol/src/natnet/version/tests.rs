use super::*;

#[test]
fn rules_and_parsing() {
    assert!(NatNetVersion::V3_0 < NatNetVersion::V3_1);
    assert!(!NatNetVersion::V4_0.has_section_sizes());
    assert!(NatNetVersion::V4_1.has_section_sizes());
    assert!(NatNetVersion::new(2, 10, 0, 0).check().is_err());
    assert!(NatNetVersion::new(5, 0, 0, 0).check().is_err());
    assert_eq!(NatNetVersion::V4_1.to_string(), "4.1.0.0");
    assert_eq!(
        parse_bitstream_reply("Bitstream,4.0"),
        Some(NatNetVersion::V4_0)
    );
    assert_eq!(
        parse_bitstream_reply("Bitstream,3.1.0"),
        Some(NatNetVersion::V3_1)
    );
    assert_eq!(parse_bitstream_reply("Bitstream,x"), None);
    assert_eq!(parse_bitstream_reply("Bitstream,1.2.3.4.5"), None);
}

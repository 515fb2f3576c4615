use super::*;

#[test]
fn vax_float_decodes_known_values() {
    // 1.0 in VAX-F is 0x4080 0x0000 (word order: high word first, each word little-endian).
    assert_eq!(Processor::Dec.f32([0x80, 0x40, 0, 0]), 1.0);
    assert_eq!(Processor::Dec.f32([0, 0, 0, 0]), 0.0);
    assert_eq!(Processor::Dec.f32([0x80, 0xC0, 0, 0]), -1.0);
}

#[test]
fn every_processor_writes_what_it_reads() {
    for p in [Processor::Intel, Processor::Dec, Processor::Mips] {
        for v in [0.0f32, 1.0, -1.0, 363.0, 70_000.0] {
            assert_eq!(p.f32(p.put_f32(v)), v, "{p:?} {v}");
        }
        for v in [0u16, 1, 363, 65_535] {
            assert_eq!(p.u16(p.put_u16(v)), v, "{p:?} {v}");
        }
    }
}

#[test]
fn mips_is_big_endian() {
    assert_eq!(Processor::Mips.i16([0x01, 0x02]), 0x0102);
    assert_eq!(Processor::Mips.f32(1.5f32.to_be_bytes()), 1.5);
}

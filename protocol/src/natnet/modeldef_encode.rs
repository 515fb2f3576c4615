//! NAT_MODELDEF encoder, for emoshift's Motive stand-in.

use super::error::NatNetEncodeError;
use super::message::{begin_packet, finish_packet, MessageId};
use super::modeldef::{AssetDef, ForcePlateDef, ModelDefs, RigidBodyDef};
use super::version::NatNetVersion;
use super::wire::{begin_size, end_size, put_count, put_cstr, put_f32s, put_i32, put_u16};

type Enc = Result<(), NatNetEncodeError>;

/// Encodes `defs` as a NAT_MODELDEF of NatNet `version` into `out` (cleared first), in type
/// order: markersets, rigid bodies, skeletons, force plates, devices, cameras, assets (4.1+
/// only: they are dropped for older versions). [`ModelDefs::skipped_types`] are not written.
///
/// # Errors
///
/// An unsupported version, a name with a NUL, a payload over 65,535 bytes.
pub fn encode_model_defs_into(defs: &ModelDefs, version: NatNetVersion, out: &mut Vec<u8>) -> Enc {
    if !version.is_supported() {
        return Err(NatNetEncodeError::UnsupportedVersion {
            major: version.major,
            minor: version.minor,
        });
    }
    let v = version;
    let assets = if v.has_section_sizes() {
        defs.assets.len()
    } else {
        0
    };
    begin_packet(out, MessageId::ModelDef);
    let n = defs.markersets.len()
        + defs.rigid_bodies.len()
        + defs.skeletons.len()
        + defs.force_plates.len()
        + defs.devices.len()
        + defs.cameras.len()
        + assets;
    put_count(out, n)?;
    put_bodies(out, v, defs)?;
    put_devices(out, v, defs, assets)?;
    finish_packet(out)
}

/// The markersets, rigid bodies and skeletons, each described.
fn put_bodies(out: &mut Vec<u8>, v: NatNetVersion, defs: &ModelDefs) -> Enc {
    for m in &defs.markersets {
        described(out, v, 0, |out| {
            put_cstr(out, &m.name)?;
            put_names(out, &m.marker_names)
        })?;
    }
    for b in &defs.rigid_bodies {
        described(out, v, 1, |out| put_rigid_body(out, v, b))?;
    }
    for s in &defs.skeletons {
        described(out, v, 2, |out| {
            put_cstr(out, &s.name)?;
            put_i32(out, s.id);
            put_count(out, s.bones.len())?;
            s.bones.iter().try_for_each(|b| put_rigid_body(out, v, b))
        })?;
    }
    Ok(())
}

/// The force plates, devices, cameras and the first `assets` assets, each described.
fn put_devices(out: &mut Vec<u8>, v: NatNetVersion, defs: &ModelDefs, assets: usize) -> Enc {
    for p in &defs.force_plates {
        described(out, v, 3, |out| put_force_plate(out, p))?;
    }
    for d in &defs.devices {
        described(out, v, 4, |out| {
            put_i32(out, d.id);
            put_cstr(out, &d.name)?;
            put_cstr(out, &d.serial)?;
            put_i32(out, d.device_type);
            put_i32(out, d.channel_data_type);
            put_names(out, &d.channel_names)
        })?;
    }
    for c in &defs.cameras {
        described(out, v, 5, |out| {
            put_cstr(out, &c.name)?;
            put_f32s(out, &c.position);
            put_f32s(out, &c.orientation);
            Ok(())
        })?;
    }
    for a in defs.assets.iter().take(assets) {
        described(out, v, 6, |out| put_asset(out, v, a))?;
    }
    Ok(())
}

/// Type, then (4.1+) the byte size of the description, then the description.
fn described(
    out: &mut Vec<u8>,
    v: NatNetVersion,
    type_id: i32,
    body: impl FnOnce(&mut Vec<u8>) -> Enc,
) -> Enc {
    put_i32(out, type_id);
    if !v.has_section_sizes() {
        return body(out);
    }
    let start = begin_size(out);
    body(out)?;
    end_size(out, start)
}

fn put_names(out: &mut Vec<u8>, names: &[String]) -> Enc {
    put_count(out, names.len())?;
    names.iter().try_for_each(|n| put_cstr(out, n))
}

fn put_rigid_body(out: &mut Vec<u8>, v: NatNetVersion, b: &RigidBodyDef) -> Enc {
    put_cstr(out, &b.name)?;
    put_i32(out, b.id);
    put_i32(out, b.parent_id);
    put_f32s(out, &b.offset);
    put_count(out, b.markers.len())?;
    b.markers.iter().for_each(|m| put_f32s(out, &m.offset));
    b.markers
        .iter()
        .for_each(|m| put_i32(out, m.required_label));
    if v.has_rigid_body_marker_names() {
        b.markers.iter().try_for_each(|m| put_cstr(out, &m.name))?;
    }
    Ok(())
}

fn put_force_plate(out: &mut Vec<u8>, p: &ForcePlateDef) -> Enc {
    put_i32(out, p.id);
    put_cstr(out, &p.serial)?;
    put_f32s(out, &p.size);
    put_f32s(out, &p.origin);
    let mut cal = [0.0f32; 144];
    for (dst, src) in cal.iter_mut().zip(&p.calibration) {
        *dst = *src;
    }
    put_f32s(out, &cal);
    p.corners.iter().for_each(|c| put_f32s(out, c));
    put_i32(out, p.plate_type);
    put_i32(out, p.channel_data_type);
    put_names(out, &p.channel_names)
}

fn put_asset(out: &mut Vec<u8>, v: NatNetVersion, a: &AssetDef) -> Enc {
    put_cstr(out, &a.name)?;
    put_i32(out, a.asset_type);
    put_i32(out, a.id);
    put_count(out, a.rigid_bodies.len())?;
    a.rigid_bodies
        .iter()
        .try_for_each(|b| put_rigid_body(out, v, b))?;
    put_count(out, a.markers.len())?;
    for (name, id, pos, size, params) in &a.markers {
        put_cstr(out, name)?;
        put_i32(out, *id);
        put_f32s(out, pos);
        put_f32s(out, &[*size]);
        put_u16(out, *params);
    }
    Ok(())
}

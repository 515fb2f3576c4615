//! NAT_MODELDEF: data descriptions of markersets, rigid bodies, skeletons, force plates,
//! devices, cameras and assets. Not on the frame path: decoding allocates freely.

use super::error::{ModelDefError, NatNetError};
use super::message::{expect_packet, MessageId, HEADER_LEN};
use super::version::NatNetVersion;
use super::wire::Reader;

/// Every description of a NAT_MODELDEF, grouped by type (order within a type is kept).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ModelDefs {
    /// Markerset descriptions (type 0).
    pub markersets: Vec<MarkersetDef>,
    /// Rigid body descriptions (type 1).
    pub rigid_bodies: Vec<RigidBodyDef>,
    /// Skeleton descriptions (type 2).
    pub skeletons: Vec<SkeletonDef>,
    /// Force plate descriptions (type 3).
    pub force_plates: Vec<ForcePlateDef>,
    /// Peripheral device descriptions (type 4).
    pub devices: Vec<DeviceDef>,
    /// Camera descriptions (type 5).
    pub cameras: Vec<CameraDef>,
    /// Asset descriptions (type 6, NatNet 4.1).
    pub assets: Vec<AssetDef>,
    /// Types of descriptions skipped because unknown (possible from 4.1, which sizes them).
    pub skipped_types: Vec<i32>,
}

impl ModelDefs {
    /// The markerset called `name`.
    pub fn markerset(&self, name: &str) -> Option<&MarkersetDef> {
        self.markersets.iter().find(|m| m.name == name)
    }

    /// The rigid body with streaming id `id`.
    pub fn rigid_body(&self, id: i32) -> Option<&RigidBodyDef> {
        self.rigid_bodies.iter().find(|b| b.id == id)
    }
}

/// A markerset: its name and its markers' names, in frame order.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MarkersetDef {
    /// Markerset name.
    pub name: String,
    /// Marker names, in the order of the frame's positions.
    pub marker_names: Vec<String>,
}

/// A rigid body (or skeleton bone, or asset rigid body).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RigidBodyDef {
    /// Name.
    pub name: String,
    /// Streaming id (bone index for skeleton bones).
    pub id: i32,
    /// Parent id, -1 for none.
    pub parent_id: i32,
    /// Offset from the parent, metres.
    pub offset: [f32; 3],
    /// Markers (NatNet 3.0+).
    pub markers: Vec<RigidBodyMarkerDef>,
}

/// A rigid body's marker.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RigidBodyMarkerDef {
    /// Offset from the rigid body's origin, metres.
    pub offset: [f32; 3],
    /// Required active label, 0 for none.
    pub required_label: i32,
    /// Name (NatNet 4.0+; empty before).
    pub name: String,
}

/// A skeleton: name, id, bones.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SkeletonDef {
    /// Name.
    pub name: String,
    /// Skeleton id.
    pub id: i32,
    /// Bones, as rigid body descriptions.
    pub bones: Vec<RigidBodyDef>,
}

/// A force plate.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ForcePlateDef {
    /// Id, as in frames.
    pub id: i32,
    /// Serial number.
    pub serial: String,
    /// Width and length.
    pub size: [f32; 2],
    /// Electrical centre offset.
    pub origin: [f32; 3],
    /// 12 × 12 calibration matrix, row-major.
    pub calibration: Vec<f32>,
    /// Corners, 4 × xyz.
    pub corners: [[f32; 3]; 4],
    /// Plate type (C3D).
    pub plate_type: i32,
    /// Channel data type (0 calibrated, 1 raw volts).
    pub channel_data_type: i32,
    /// Channel names.
    pub channel_names: Vec<String>,
}

/// A peripheral device (analog input).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct DeviceDef {
    /// Id, as in frames.
    pub id: i32,
    /// Name.
    pub name: String,
    /// Serial number.
    pub serial: String,
    /// Device type code.
    pub device_type: i32,
    /// Channel data type code.
    pub channel_data_type: i32,
    /// Channel names.
    pub channel_names: Vec<String>,
}

/// A camera.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CameraDef {
    /// Name.
    pub name: String,
    /// Position, metres.
    pub position: [f32; 3],
    /// Orientation quaternion `qx, qy, qz, qw`.
    pub orientation: [f32; 4],
}

/// A NatNet 4.1 asset (trained markerset): its rigid bodies and markers.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AssetDef {
    /// Name.
    pub name: String,
    /// Asset type code.
    pub asset_type: i32,
    /// Id.
    pub id: i32,
    /// Rigid bodies.
    pub rigid_bodies: Vec<RigidBodyDef>,
    /// Markers: name, id, initial position, size, params.
    pub markers: Vec<(String, i32, [f32; 3], f32, u16)>,
}

type R<T> = Result<T, NatNetError>;

/// Decodes a NAT_MODELDEF datagram (header included) of NatNet `version`.
///
/// # Errors
///
/// [`ModelDefError::Packet`] for framing, version and count errors;
/// [`ModelDefError::Description`] naming the description that is malformed, of an unknown
/// type (before 4.1, which cannot skip it), or whose 4.1 size disagrees with its content.
pub fn decode_model_defs(
    datagram: &[u8],
    version: NatNetVersion,
) -> Result<ModelDefs, ModelDefError> {
    version.check().map_err(ModelDefError::Packet)?;
    expect_packet(datagram, MessageId::ModelDef).map_err(ModelDefError::Packet)?;
    let r = &mut Reader::at(datagram, HEADER_LEN);
    let min = if version.has_section_sizes() { 8 } else { 4 };
    let n = r.count(min).map_err(ModelDefError::Packet)?;
    let mut defs = ModelDefs::default();
    for index in 0..n {
        let type_id = r.i32().map_err(ModelDefError::Packet)?;
        description(r, version, type_id, &mut defs).map_err(|source| {
            ModelDefError::Description {
                index,
                type_id,
                source,
            }
        })?;
    }
    r.finish().map_err(ModelDefError::Packet)?;
    Ok(defs)
}

fn description(r: &mut Reader<'_>, v: NatNetVersion, type_id: i32, defs: &mut ModelDefs) -> R<()> {
    let sized = if v.has_section_sizes() {
        let at = r.pos();
        Some((at, r.count(1)?, r.pos()))
    } else {
        None
    };
    match type_id {
        0 => defs.markersets.push(MarkersetDef {
            name: r.cstr()?.to_owned(),
            marker_names: names(r)?,
        }),
        1 => defs.rigid_bodies.push(rigid_body(r, v)?),
        2 => defs.skeletons.push(SkeletonDef {
            name: r.cstr()?.to_owned(),
            id: r.i32()?,
            bones: list(r, 4 + 4 + 4 + 12, |r| rigid_body(r, v))?,
        }),
        3 => defs.force_plates.push(force_plate(r)?),
        4 => defs.devices.push(DeviceDef {
            id: r.i32()?,
            name: r.cstr()?.to_owned(),
            serial: r.cstr()?.to_owned(),
            device_type: r.i32()?,
            channel_data_type: r.i32()?,
            channel_names: names(r)?,
        }),
        5 => defs.cameras.push(CameraDef {
            name: r.cstr()?.to_owned(),
            position: r.vec3()?,
            orientation: r.quat()?,
        }),
        6 => defs.assets.push(asset(r, v)?),
        _ => match sized {
            Some((_, size, _)) => {
                r.skip(size)?;
                defs.skipped_types.push(type_id);
            }
            None => {
                return Err(NatNetError::UnknownDescription {
                    type_id,
                    offset: r.pos() - 4,
                })
            }
        },
    }
    if let Some((offset, declared, start)) = sized {
        let actual = r.pos() - start;
        if actual != declared {
            return Err(NatNetError::SectionSize {
                offset,
                declared,
                actual,
            });
        }
    }
    Ok(())
}

fn list<T>(
    r: &mut Reader<'_>,
    min: usize,
    mut item: impl FnMut(&mut Reader<'_>) -> R<T>,
) -> R<Vec<T>> {
    let n = r.count(min)?;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        out.push(item(r)?);
    }
    Ok(out)
}

fn names(r: &mut Reader<'_>) -> R<Vec<String>> {
    list(r, 1, |r| r.cstr().map(str::to_owned))
}

fn rigid_body(r: &mut Reader<'_>, v: NatNetVersion) -> R<RigidBodyDef> {
    let name = r.cstr()?.to_owned();
    let id = r.i32()?;
    let parent_id = r.i32()?;
    let offset = r.vec3()?;
    // 3.0+: n, n offsets, n required labels, (4.0+) n names: three parallel arrays.
    let per_marker = 12 + 4 + usize::from(v.has_rigid_body_marker_names());
    let n = r.count(per_marker)?;
    let mut markers = Vec::with_capacity(n);
    for _ in 0..n {
        markers.push(RigidBodyMarkerDef {
            offset: r.vec3()?,
            ..RigidBodyMarkerDef::default()
        });
    }
    for m in &mut markers {
        m.required_label = r.i32()?;
    }
    if v.has_rigid_body_marker_names() {
        for m in &mut markers {
            m.name = r.cstr()?.to_owned();
        }
    }
    Ok(RigidBodyDef {
        name,
        id,
        parent_id,
        offset,
        markers,
    })
}

fn force_plate(r: &mut Reader<'_>) -> R<ForcePlateDef> {
    let id = r.i32()?;
    let serial = r.cstr()?.to_owned();
    let size = [r.f32()?, r.f32()?];
    let origin = r.vec3()?;
    let mut calibration = Vec::with_capacity(144);
    for _ in 0..144 {
        calibration.push(r.f32()?);
    }
    let corners = [r.vec3()?, r.vec3()?, r.vec3()?, r.vec3()?];
    Ok(ForcePlateDef {
        id,
        serial,
        size,
        origin,
        calibration,
        corners,
        plate_type: r.i32()?,
        channel_data_type: r.i32()?,
        channel_names: names(r)?,
    })
}

fn asset(r: &mut Reader<'_>, v: NatNetVersion) -> R<AssetDef> {
    Ok(AssetDef {
        name: r.cstr()?.to_owned(),
        asset_type: r.i32()?,
        id: r.i32()?,
        rigid_bodies: list(r, 1 + 4 + 4 + 12 + 4, |r| rigid_body(r, v))?,
        markers: list(r, 1 + 4 + 12 + 4 + 2, |r| {
            Ok((
                r.cstr()?.to_owned(),
                r.i32()?,
                r.vec3()?,
                r.f32()?,
                r.u16()?,
            ))
        })?,
    })
}

//! The parameters QTM gives in answer to `GetParameters`: XML rooted at
//! `QTM_Parameters_Ver_<major>.<minor>`, with `General` (the capture rate) and `The_3D` (the
//! labelled markers, in the order of the `3D` component's markers). emoshift writes them as a
//! server ([`encode_parameters_into`]); the writer is small and escapes every name, so no XML
//! crate is needed on this side.

use std::fmt::Write as _;

use super::command::ParameterSet;
use super::packet::{encode_text_into, PacketType};

/// What emoshift tells clients about its frames.
#[derive(Debug, Clone, Copy)]
pub struct Parameters<'a> {
    /// The protocol version the client agreed (it names the root element).
    pub version: (u32, u32),
    /// Frames a second.
    pub frequency_hz: u32,
    /// The labels, in marker order.
    pub labels: &'a [String],
}

/// Writes the XML packet for `set` into `out` (cleared first).
pub fn encode_parameters_into(p: &Parameters<'_>, set: ParameterSet, out: &mut Vec<u8>) {
    let mut xml = String::with_capacity(256 + 96 * p.labels.len());
    let (major, minor) = p.version;
    let _ = writeln!(xml, "<QTM_Parameters_Ver_{major}.{minor:02}>");
    if set.general {
        let _ = write!(
            xml,
            "  <General>\n    <Frequency>{}</Frequency>\n    <Capture_Time>0.000000</Capture_Time>\n    \
             <Start_On_External_Trigger>false</Start_On_External_Trigger>\n    \
             <Start_On_Trigger_NO>false</Start_On_Trigger_NO>\n    \
             <Start_On_Trigger_NC>false</Start_On_Trigger_NC>\n    \
             <Start_On_Trigger_Software>false</Start_On_Trigger_Software>\n    \
             <External_Time_Base>\n      <Enabled>false</Enabled>\n    </External_Time_Base>\n    \
             <External_Timestamp>\n      <Enabled>false</Enabled>\n      <Type>SMPTE</Type>\n      \
             <Frequency>{}</Frequency>\n    </External_Timestamp>\n  </General>\n",
            p.frequency_hz, p.frequency_hz
        );
    }
    if set.d3 {
        let _ = write!(
            xml,
            "  <The_3D>\n    <AxisUpwards>+Y</AxisUpwards>\n    <CalibrationTime></CalibrationTime>\n    \
             <Labels>{}</Labels>\n",
            p.labels.len()
        );
        for label in p.labels {
            xml.push_str("    <Label>\n      <Name>");
            escape_into(label, &mut xml);
            xml.push_str(
                "</Name>\n      <RGBColor>16711680</RGBColor>\n      \
                 <Trajectory_Type>Measured</Trajectory_Type>\n    </Label>\n",
            );
        }
        xml.push_str("    <Bones></Bones>\n  </The_3D>\n");
    }
    let _ = writeln!(xml, "</QTM_Parameters_Ver_{major}.{minor:02}>");
    encode_text_into(PacketType::Xml, &xml, out);
}

/// `text` with XML's five special characters escaped, and control characters (not allowed
/// in XML 1.0) as `?`.
fn escape_into(text: &str, out: &mut String) {
    for c in text.chars() {
        match c {
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '&' => out.push_str("&amp;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if c.is_control() => out.push('?'),
            c => out.push(c),
        }
    }
}

//! QTM's parameters as a client reads them: the capture frequency (`General/Frequency`) and
//! the labelled markers (`The_3D/Label/Name`, in the order of the `3D` component's markers).
//! Parsed with quick-xml (well kept, streaming, no DOM, no entity expansion beyond XML's five):
//! QTM's XML carries attributes, comments and nesting a hand-rolled scanner would get wrong.

use quick_xml::events::Event as XmlEvent;
use quick_xml::Reader;

/// Labels read at most (QTM's own limit is far below; this bounds a hostile server).
pub const MAX_LABELS: usize = 10_000;

/// What a QTM source needs of the parameters.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct QtmParameters {
    /// `General/Frequency`, when given.
    pub frequency_hz: Option<f64>,
    /// `The_3D`'s label names, in marker order; `None` when the XML had no `The_3D`.
    pub labels: Option<Vec<String>>,
}

/// Why parameters could not be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ParametersError {
    /// Not well-formed XML.
    #[error("parameters are not well-formed XML at byte {offset}")]
    Malformed {
        /// Where the reader stopped.
        offset: u64,
    },
    /// More labels than [`MAX_LABELS`].
    #[error("more than {MAX_LABELS} labels")]
    TooManyLabels,
}

/// Reads `General/Frequency` and `The_3D/Label/Name` from a `GetParameters` answer.
///
/// # Errors
/// Malformed XML, or too many labels.
pub fn decode_parameters(xml: &str) -> Result<QtmParameters, ParametersError> {
    let mut reader = Reader::from_str(xml);
    let mut path: Vec<Vec<u8>> = Vec::with_capacity(8);
    let mut out = QtmParameters::default();
    loop {
        let event = reader
            .read_event()
            .map_err(|_| ParametersError::Malformed {
                offset: reader.buffer_position(),
            })?;
        match event {
            XmlEvent::Start(e) => {
                let name = e.name().as_ref().to_vec();
                if name == b"The_3D" && path.len() == 1 {
                    out.labels = Some(Vec::new());
                }
                path.push(name);
            }
            XmlEvent::End(_) => {
                path.pop();
            }
            XmlEvent::Empty(e) if e.name().as_ref() == b"The_3D" && path.len() == 1 => {
                out.labels = Some(Vec::new());
            }
            XmlEvent::Text(t) => {
                let text = t.unescape().map_err(|_| ParametersError::Malformed {
                    offset: reader.buffer_position(),
                })?;
                let at = |p: &[&[u8]]| {
                    path.len() == p.len() + 1 && path[1..].iter().zip(p).all(|(a, b)| a == b)
                };
                if at(&[b"General", b"Frequency"]) {
                    out.frequency_hz = text.trim().parse().ok();
                } else if at(&[b"The_3D", b"Label", b"Name"]) {
                    let labels = out.labels.get_or_insert_with(Vec::new);
                    if labels.len() >= MAX_LABELS {
                        return Err(ParametersError::TooManyLabels);
                    }
                    labels.push(text.into_owned());
                }
            }
            XmlEvent::Eof => break,
            _ => {}
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_what_the_writer_writes_and_qtms_own_layout() {
        let labels = vec!["A&B".to_string(), "Alice_Brow".to_string()];
        let p = super::super::Parameters {
            version: (1, 25),
            frequency_hz: 120,
            labels: &labels,
        };
        let mut out = Vec::new();
        let all = super::super::ParameterSet {
            general: true,
            d3: true,
        };
        super::super::encode_parameters_into(&p, all, &mut out);
        let xml = std::str::from_utf8(&out[8..out.len() - 1]).expect("utf-8");
        let got = decode_parameters(xml).expect("valid");
        assert_eq!(got.frequency_hz, Some(120.0));
        assert_eq!(got.labels.as_deref(), Some(&labels[..]));
        let qtm = "<QTM_Parameters_Ver_1.25><!-- c --><The_3D><AxisUpwards>+Z</AxisUpwards>\
                   <Labels>1</Labels><Label><Name>VF_Spine</Name><RGBColor>1</RGBColor></Label>\
                   <Bones><Bone From=\"a\" To=\"b\"/></Bones></The_3D></QTM_Parameters_Ver_1.25>";
        let got = decode_parameters(qtm).expect("valid");
        assert_eq!(
            (got.frequency_hz, got.labels),
            (None, Some(vec!["VF_Spine".into()]))
        );
        assert!(decode_parameters("<a><b></a>").is_err());
    }
}

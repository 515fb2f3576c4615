//! QTM's events: one byte in an event packet, sent when QTM's state changes and in answer to
//! `GetState`.

/// An event, numbered as QTM numbers them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[allow(missing_docs)] // The names are QTM's.
pub enum Event {
    Connected = 1,
    ConnectionClosed = 2,
    CaptureStarted = 3,
    CaptureStopped = 4,
    CaptureFetchingFinished = 5,
    CalibrationStarted = 6,
    CalibrationStopped = 7,
    RtFromFileStarted = 8,
    RtFromFileStopped = 9,
    WaitingForTrigger = 10,
    CameraSettingsChanged = 11,
    QtmShuttingDown = 12,
    CaptureSaved = 13,
    ReprocessingStarted = 14,
    ReprocessingStopped = 15,
    Trigger = 16,
}

impl Event {
    /// The event from its byte.
    pub fn from_u8(b: u8) -> Option<Event> {
        use Event::*;
        Some(match b {
            1 => Connected,
            2 => ConnectionClosed,
            3 => CaptureStarted,
            4 => CaptureStopped,
            5 => CaptureFetchingFinished,
            6 => CalibrationStarted,
            7 => CalibrationStopped,
            8 => RtFromFileStarted,
            9 => RtFromFileStopped,
            10 => WaitingForTrigger,
            11 => CameraSettingsChanged,
            12 => QtmShuttingDown,
            13 => CaptureSaved,
            14 => ReprocessingStarted,
            15 => ReprocessingStopped,
            16 => Trigger,
            _ => return None,
        })
    }

    /// The event's byte.
    pub fn as_u8(self) -> u8 {
        self as u8
    }

    /// Whether a client must read the parameters again: the labels or the rate may have
    /// changed (settings changed, a capture or RT-from-file started or stopped).
    pub fn rereads_parameters(self) -> bool {
        matches!(
            self,
            Event::CameraSettingsChanged
                | Event::CaptureStarted
                | Event::CaptureStopped
                | Event::RtFromFileStarted
                | Event::RtFromFileStopped
                | Event::Connected
        )
    }

    /// Whether the stream ends (QTM closes the measurement or quits).
    pub fn ends_stream(self) -> bool {
        matches!(self, Event::ConnectionClosed | Event::QtmShuttingDown)
    }
}

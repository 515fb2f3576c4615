//! The processing thread's one wait: the OSC frame socket, which the thread reads itself (so an
//! OSC frame is received, processed and sent without a hand-off between threads, as a relay
//! would), and the [`Doorbell`] the queue, control and shutdown ring. The wait is
//! edge-triggered: once the socket is readable it is read until it would block. A timed wait
//! ends on a timerfd, to the nanosecond: mio's own timeout is rounded up to whole
//! milliseconds, which would wake the thread after a steady source's next frame instead of
//! just before it ([`crate::serve::arrival`]).

use std::io;
use std::net::SocketAddr;
use std::os::fd::{AsRawFd, OwnedFd};
use std::time::Duration;

use mio::net::UdpSocket;
use mio::unix::SourceFd;
use mio::{Events, Interest, Poll, Token, Waker};
use rustix::time::{Itimerspec, TimerfdClockId, TimerfdFlags, TimerfdTimerFlags, Timespec};

use crate::serve::wake::Doorbell;

const SOCKET: Token = Token(0);
const BELL: Token = Token(1);
const TIMER: Token = Token(2);

/// The frame socket and the bell, waited on together.
pub(crate) struct Inbox {
    poll: Poll,
    events: Events,
    /// `None` once shutdown stopped reading.
    socket: Option<UdpSocket>,
    /// The socket may hold datagrams not read yet.
    readable: bool,
    /// Ends timed waits (monotonic clock, non-blocking).
    timer: OwnedFd,
    /// The bell's waker stays open while the poll waits on it, however many rings are gone
    /// (a closed eventfd leaves the poll's interest list, and its last ring with it).
    _bell: Doorbell,
}

impl Inbox {
    /// Waits on `socket` (made non-blocking) and on the bell it returns.
    ///
    /// # Errors
    /// The OS refuses a poll instance, the registration or the waker.
    pub(crate) fn new(socket: std::net::UdpSocket) -> io::Result<(Inbox, Doorbell)> {
        socket.set_nonblocking(true)?;
        let poll = Poll::new()?;
        let mut socket = UdpSocket::from_std(socket);
        poll.registry()
            .register(&mut socket, SOCKET, Interest::READABLE)?;
        let bell = Doorbell::new(Waker::new(poll.registry(), BELL)?);
        let flags = TimerfdFlags::NONBLOCK | TimerfdFlags::CLOEXEC;
        let timer = rustix::time::timerfd_create(TimerfdClockId::Monotonic, flags)?;
        poll.registry()
            .register(&mut SourceFd(&timer.as_raw_fd()), TIMER, Interest::READABLE)?;
        let inbox = Inbox {
            poll,
            events: Events::with_capacity(8),
            socket: Some(socket),
            // Datagrams may have come between the bind and the registration.
            readable: true,
            timer,
            _bell: bell.clone(),
        };
        Ok((inbox, bell))
    }

    /// Waits at most `timeout` for a datagram or the bell (not at all while the socket may
    /// still hold datagrams); whether anything came.
    pub(crate) fn wait(&mut self, timeout: Duration) -> bool {
        let timeout = if self.readable {
            Duration::ZERO
        } else if timeout.subsec_nanos() % 1_000_000 != 0 && self.arm(timeout) {
            // The timer ends it; mio's rounded-up timeout is only a safety net.
            timeout + Duration::from_millis(1)
        } else {
            timeout
        };
        if let Err(e) = self.poll.poll(&mut self.events, Some(timeout)) {
            if e.kind() != io::ErrorKind::Interrupted {
                tracing::warn!(target: "emoshift", error = %e, "waiting for frames failed");
            }
            return self.readable;
        }
        let mut rang = false;
        for event in &self.events {
            match event.token() {
                SOCKET => self.readable = true,
                // Expired: read, so that the next expiry is an edge again.
                TIMER => _ = rustix::io::read(&self.timer, &mut [0u8; 8]),
                _ => rang = true,
            }
        }
        rang || self.readable
    }

    /// Sets the timer to expire `after` from now (a timer still set from an earlier wait is
    /// replaced); `false` if the OS refused.
    fn arm(&self, after: Duration) -> bool {
        let zero = Timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        let value = Timespec {
            tv_sec: after.as_secs().try_into().unwrap_or(i64::MAX),
            tv_nsec: after.subsec_nanos().into(),
        };
        let spec = Itimerspec {
            it_interval: zero,
            it_value: value,
        };
        rustix::time::timerfd_settime(&self.timer, TimerfdTimerFlags::empty(), &spec).is_ok()
    }

    /// Whether the socket may still hold datagrams (read it before waiting).
    pub(crate) fn pending(&self) -> bool {
        self.readable
    }

    /// The next datagram on the socket, into `buf`; `None` once none is waiting.
    pub(crate) fn recv(&mut self, buf: &mut [u8]) -> Option<(usize, SocketAddr)> {
        let socket = self.socket.as_ref().filter(|_| self.readable)?;
        loop {
            match socket.recv_from(buf) {
                Ok(got) => return Some(got),
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    self.readable = false;
                    return None;
                }
                // ICMP errors and the like on a UDP socket (each read once): go on.
                Err(e) => {
                    tracing::trace!(target: "emoshift", error = %e, "frame socket receive error");
                }
            }
        }
    }

    /// Stops reading the socket (shutdown); datagrams still on it are left unread.
    pub(crate) fn close_socket(&mut self) {
        if let Some(mut socket) = self.socket.take() {
            let _ = self.poll.registry().deregister(&mut socket);
        }
        self.readable = false;
    }
}

#[cfg(test)]
mod tests;

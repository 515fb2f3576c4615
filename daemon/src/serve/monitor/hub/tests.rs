use super::*;

#[test]
fn a_page_that_does_not_read_loses_feed_messages_and_then_its_connection_never_memory() {
    let board = Arc::new(Board::new());
    let hub = Hub::new(Arc::clone(&board));
    let mut slow = hub.join().expect("room");
    let mut quick = hub.join().expect("room");
    assert!(board.watched());
    for k in 0..100u8 {
        hub.feed(vec![k; 16]);
        // The quick page reads as fast as it is fed.
        assert!(quick.feed.try_recv().is_ok());
    }
    assert_eq!(hub.dropped.load(Ordering::Relaxed), 100 - FEED_QUEUE as u64);
    let mut queued = 0;
    while slow.feed.try_recv().is_ok() {
        queued += 1;
    }
    assert_eq!(queued, FEED_QUEUE, "the slow page's queue never grew");
    for _ in 0..TEXT_QUEUE {
        hub.text("{}");
        assert!(quick.texts.try_recv().is_ok());
    }
    assert_eq!(
        hub.counters().viewers,
        2,
        "a full text queue is still in time"
    );
    hub.text("{}");
    assert_eq!(
        hub.counters().viewers,
        1,
        "one more and the slow page is dropped"
    );
    hub.leave(quick.id);
    assert!(
        !board.watched(),
        "no page open: the processing thread copies nothing"
    );
}

#[test]
fn no_more_than_max_viewers() {
    let hub = Hub::new(Arc::new(Board::new()));
    let pages: Vec<Joined> = (0..MAX_VIEWERS).filter_map(|_| hub.join()).collect();
    assert_eq!(pages.len(), MAX_VIEWERS);
    assert!(hub.full() && hub.join().is_none());
}

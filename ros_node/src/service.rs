//! Service servers in the request/reply mapping of `rmw_cyclonedds_cpp`, shared by the
//! simulator-control services ([`crate::control`]), the parameter services
//! ([`crate::params`]) and the action's services ([`crate::action`]), and the delivery of
//! their replies.
//!
//! A client learns that the service is there when *its* endpoints have matched the server's
//! (rclcpp's `wait_for_service`); the server's reply writer may not yet have matched the
//! client's reply reader. A volatile writer never delivers a sample written before a reader
//! matched, so a reply written then is lost and the client waits forever. The node therefore
//! holds each reply in an [`Outbox`] until its writer has matched the client's reply reader,
//! reported by [`ReplyReaders`], and the first reply to a reader [`FIRST_REPLY_DELAY`] more,
//! for the reader's first heartbeat. `rmw_cyclonedds_cpp`'s `rmw_send_response` waits for
//! the same match (blocking, for at most 100 ms); the node's loop goes on while a reply
//! waits.

use ros2_client::dds::rustdds::{
    DomainParticipant, DomainParticipantStatusEvent, StatusEvented, GUID,
};
use ros2_client::dds::{Node as RosNode, Server, ServiceMapping};
use ros2_client::service::RmwRequestId;
use ros2_client::{Message, Name, NodeName, QosProfile, ServiceTypeName};
use std::collections::{HashMap, HashSet};
use std::fmt::Debug;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long a reply waits for its client's reply reader to match before it is written
/// anyway (with a warning): discovery can take seconds on a loaded machine.
pub const HOLD: Duration = Duration::from_secs(10);

/// How long the first reply to a client's reply reader waits after both its request arrived
/// and the node's writer matched the reader.
///
/// A Cyclone DDS volatile reader (rclcpp's default through `rmw_cyclonedds_cpp`) accepts no
/// data from another vendor's writer before it has processed a heartbeat from it, and takes
/// that first heartbeat's last sequence number as the start of the session: what the writer
/// had written by then is never delivered ("the first samples written after matching the
/// reader may be lost", in Cyclone's source). The reader asks for that heartbeat once it has
/// matched the writer (a pre-emptive ACKNACK, 10 ms later in the traces), and the client
/// sends its request only after that match. A reply written at once can be data that the
/// first heartbeat already counts: rustdds sends the data by multicast and its answer to the
/// ACKNACK by unicast, and a loaded receiver can take them in either order (measured with
/// both cores busy: 4 of 42 rounds of the ROS tests lost a reply so without this delay, none
/// of 45 with it). Waiting this long lets the reader process a heartbeat first; later
/// replies to the same reader go out at once.
pub const FIRST_REPLY_DELAY: Duration = Duration::from_millis(200);

/// How often the watcher thread drains the participant's status events.
const WATCH_PERIOD: Duration = Duration::from_millis(1);

/// The server of service `base/service` of type `package/srv/ty`, in the request/reply
/// mapping of `rmw_cyclonedds_cpp` (a header of the client's GUID and a sequence number
/// before the request or reply), with its outbox.
///
/// # Errors
///
/// A bad service name, or DDS could not create the server.
pub(crate) fn server<Req, Resp>(
    node: &mut RosNode,
    readers: &Arc<ReplyReaders>,
    base: &str,
    service: &str,
    package: &str,
    ty: &str,
    qos: &QosProfile,
) -> Result<Service<Req, Resp>, String>
where
    Req: Message + Clone + 'static,
    Resp: Message + 'static,
{
    let name = Name::new(base, service).map_err(|e| format!("service {base}/{service}: {e:?}"))?;
    let server = node
        .create_server(
            ServiceMapping::Cyclone,
            &name,
            &ServiceTypeName::new(package, ty),
            qos.clone(),
            qos.clone(),
        )
        .map_err(|e| format!("cannot serve {base}/{service}: {e:?}"))?;
    Ok(Service {
        server,
        outbox: Outbox::new(&reply_topic(node, &name, "")?),
        readers: Arc::clone(readers),
    })
}

/// The DDS topic of the replies of service `name` + `suffix` of `node` (`rr<name><suffix>Reply`,
/// the namespace added to a relative name), e.g. `rr/rkforge/get_parametersReply`.
///
/// # Errors
///
/// The node's namespace is not a valid ROS 2 namespace.
pub(crate) fn reply_topic(node: &RosNode, name: &Name, suffix: &str) -> Result<String, String> {
    // Only the node's namespace enters the DDS name of a relative service name.
    let node_name = NodeName::new(node.namespace(), "rkforge")
        .map_err(|e| format!("namespace {}: {e:?}", node.namespace()))?;
    Ok(name.to_dds_name("rr", &node_name, &format!("{suffix}Reply")))
}

/// A service server and the replies it holds for clients not yet matched.
pub(crate) struct Service<Req: Message, Resp: Message> {
    server: Server<Req, Resp>,
    outbox: Outbox<Resp>,
    readers: Arc<ReplyReaders>,
}

impl<Req, Resp> Service<Req, Resp>
where
    Req: Message + 'static,
    Resp: Message + 'static,
{
    /// The next request received, if any. A request that cannot be read is reported on
    /// stderr and ends this round of taking (the client gets no reply, as from any ROS 2
    /// server).
    pub(crate) fn take(&self) -> Option<(RmwRequestId, Req)> {
        self.outbox.received(self.server.receive_request())
    }

    /// Reply `response` to request `id`: now if the client's reply reader has matched (and,
    /// for its first reply, has had time for a heartbeat), otherwise later (see [`Outbox`]).
    pub(crate) fn reply(&mut self, id: RmwRequestId, response: Resp) {
        self.outbox.push(id, response, Instant::now());
        self.flush();
    }

    /// Write the replies held whose clients can now receive them; true if replies still
    /// wait.
    pub(crate) fn flush(&mut self) -> bool {
        for (id, response) in self.outbox.ready(&self.readers) {
            self.outbox.written(self.server.send_response(id, response));
        }
        !self.outbox.is_empty()
    }
}

/// A reply held for its client.
struct Held<T> {
    id: RmwRequestId,
    since: Instant,
    reply: T,
}

/// The replies of one service's reply topic (`rr/NS/SERVICEReply`) that wait for their
/// client's reply reader to match, in the order received, and the readers answered so far.
pub(crate) struct Outbox<T> {
    topic: String,
    held: Vec<Held<T>>,
    answered: HashSet<GUID>,
}

impl<T> Outbox<T> {
    /// An empty outbox for the DDS reply topic `topic`.
    pub(crate) fn new(topic: &str) -> Outbox<T> {
        Outbox {
            topic: topic.to_owned(),
            held: Vec::new(),
            answered: HashSet::new(),
        }
    }

    /// The service, for messages: the reply topic without its `rr` prefix and `Reply` suffix.
    pub(crate) fn service(&self) -> &str {
        let t = self.topic.strip_prefix("rr").unwrap_or(&self.topic);
        t.strip_suffix("Reply").unwrap_or(t)
    }

    /// The request that `r` (a server's take) gives, if any; an error is reported on stderr
    /// and ends this round of taking (the client gets no reply, as from any ROS 2 server).
    pub(crate) fn received<R, E: Debug>(&self, r: Result<Option<R>, E>) -> Option<R> {
        r.unwrap_or_else(|e| {
            eprintln!("warning: unreadable request on {}: {e:?}", self.service());
            None
        })
    }

    /// Report on stderr a reply that DDS did not take (`r`, a server's write).
    pub(crate) fn written<E: Debug>(&self, r: Result<(), E>) {
        if let Err(e) = r {
            eprintln!("warning: reply on {} not written: {e:?}", self.service());
        }
    }

    /// True if no reply waits.
    pub(crate) fn is_empty(&self) -> bool {
        self.held.is_empty()
    }

    /// Hold `reply` to request `id`, received at `now`.
    pub(crate) fn push(&mut self, id: RmwRequestId, reply: T, now: Instant) {
        self.held.push(Held {
            id,
            since: now,
            reply,
        });
    }

    /// Take out the replies to write now (see [`Outbox::ready_at`]).
    pub(crate) fn ready(&mut self, readers: &ReplyReaders) -> Vec<(RmwRequestId, T)> {
        if self.held.is_empty() {
            return Vec::new();
        }
        self.ready_at(Instant::now(), |topic, id| readers.matched(topic, id))
    }

    /// Take out the replies to write at `now`, in the order received: those whose client's
    /// reply reader has matched (`matched(reply topic, request)` gives the reader and the
    /// time of the match) and has been answered before, or [`FIRST_REPLY_DELAY`] has passed
    /// since both the request and the match; and those held longer than [`HOLD`] (with a
    /// warning: the client may never see them).
    fn ready_at(
        &mut self,
        now: Instant,
        matched: impl Fn(&str, RmwRequestId) -> Option<(GUID, Instant)>,
    ) -> Vec<(RmwRequestId, T)> {
        let mut ready = Vec::new();
        for h in std::mem::take(&mut self.held) {
            let waited = now.duration_since(h.since);
            let go = match matched(&self.topic, h.id) {
                Some((reader, at))
                    if self.answered.contains(&reader)
                        || now.duration_since(at.max(h.since)) >= FIRST_REPLY_DELAY =>
                {
                    self.answered.insert(reader);
                    true
                }
                _ if waited >= HOLD => {
                    eprintln!(
                        "warning: the reply reader of the client of {} has not matched after {} s; the reply is written anyway",
                        self.service(),
                        HOLD.as_secs()
                    );
                    true
                }
                _ => false,
            };
            if go {
                ready.push((h.id, h.reply));
            } else {
                self.held.push(h);
            }
        }
        ready
    }
}

/// The remote readers that the node's writers have matched, from the participant's
/// `RemoteReaderMatched` events, which a thread collects as they come.
pub struct ReplyReaders {
    participant: DomainParticipant,
    /// Each reader matched and when the watcher saw it.
    matched: Arc<Mutex<HashMap<GUID, Instant>>>,
    stop: Arc<AtomicBool>,
    watcher: Option<JoinHandle<()>>,
}

impl ReplyReaders {
    /// Start collecting the readers that the writers of `participant` match.
    ///
    /// # Errors
    ///
    /// The thread could not be started.
    pub fn watch(participant: DomainParticipant) -> Result<ReplyReaders, String> {
        let matched = Arc::new(Mutex::new(HashMap::new()));
        let stop = Arc::new(AtomicBool::new(false));
        let listener = participant.status_listener();
        let (m, s) = (Arc::clone(&matched), Arc::clone(&stop));
        let watcher = std::thread::Builder::new()
            .name("rkforge-matches".into())
            .spawn(move || {
                while !s.load(Ordering::Relaxed) {
                    while let Some(event) = listener.try_recv_status() {
                        if let DomainParticipantStatusEvent::RemoteReaderMatched {
                            remote_reader,
                            ..
                        } = event
                        {
                            m.lock()
                                .unwrap_or_else(PoisonError::into_inner)
                                .entry(remote_reader)
                                .or_insert_with(Instant::now);
                        }
                    }
                    std::thread::sleep(WATCH_PERIOD);
                }
            })
            .map_err(|e| format!("cannot start the thread that watches DDS matches: {e}"))?;
        Ok(ReplyReaders {
            participant,
            matched,
            stop,
            watcher: Some(watcher),
        })
    }

    /// The reader on DDS topic `topic` in the participant of the client of request `id` and
    /// when the node's writer matched it, if it has. The Cyclone request header carries the
    /// first 8 bytes of the client's GUID prefix (the participant's), so clients in two
    /// participants of one process whose prefixes share those bytes are not told apart.
    pub fn matched(&self, topic: &str, id: RmwRequestId) -> Option<(GUID, Instant)> {
        let client = id.writer_gid.to_bytes16();
        let matched = self.matched.lock().unwrap_or_else(PoisonError::into_inner);
        self.participant
            .discovered_readers()
            .iter()
            .map(|r| (r, r.reader_proxy.remote_reader_guid))
            .filter(|(r, guid)| {
                r.subscription_topic_data.topic_name == topic && guid.to_bytes()[..8] == client[..8]
            })
            .find_map(|(_, guid)| matched.get(&guid).map(|at| (guid, *at)))
    }
}

impl Drop for ReplyReaders {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(w) = self.watcher.take() {
            let _ = w.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ros2_client::Gid;

    const TOPIC: &str = "rr/rkforge/get_simulation_stateReply";

    /// Request `seq` of the client whose participant's GUID prefix begins with byte `client`.
    fn request(client: u8, seq: i64) -> RmwRequestId {
        let mut gid = [0; 16];
        gid[0] = client;
        RmwRequestId {
            writer_gid: Gid::from(gid),
            sequence_number: seq,
        }
    }

    /// The reply reader of client `client` (see [`request`]).
    fn reader(client: u8) -> GUID {
        let mut guid = [0; 16];
        guid[0] = client;
        guid[15] = 4;
        GUID::from_bytes(guid)
    }

    /// When the readers of [`all_matched`] matched.
    fn long_ago() -> Instant {
        static T: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
        *T.get_or_init(Instant::now)
    }

    /// Every client's reply reader has matched, at [`long_ago`].
    fn all_matched(topic: &str, id: RmwRequestId) -> Option<(GUID, Instant)> {
        (topic == TOPIC).then(|| (reader(id.writer_gid.to_bytes16()[0]), long_ago()))
    }

    #[test]
    fn the_first_reply_to_a_reader_waits_the_delay_and_later_ones_go_at_once() {
        let t0 = long_ago() + Duration::from_secs(1);
        let mut outbox = Outbox::new(TOPIC);
        outbox.push(request(1, 1), "first", t0);
        assert!(outbox.ready_at(t0, all_matched).is_empty());
        let early = t0 + FIRST_REPLY_DELAY - Duration::from_millis(1);
        assert!(outbox.ready_at(early, all_matched).is_empty());
        let ready = outbox.ready_at(t0 + FIRST_REPLY_DELAY, all_matched);
        assert_eq!(ready, vec![(request(1, 1), "first")]);
        let t1 = t0 + Duration::from_secs(1);
        outbox.push(request(1, 2), "second", t1);
        let second = outbox.ready_at(t1, all_matched);
        assert_eq!(second, vec![(request(1, 2), "second")]);
        assert!(outbox.is_empty());
        assert_eq!(outbox.service(), "/rkforge/get_simulation_state");
    }

    #[test]
    fn a_reader_that_matches_after_the_request_gets_the_delay_from_its_match() {
        let t0 = Instant::now();
        let mut outbox = Outbox::new(TOPIC);
        outbox.push(request(1, 1), "a", t0);
        let match_at = t0 + Duration::from_secs(2);
        let matched = |_: &str, _| Some((reader(1), match_at));
        assert!(outbox.ready_at(match_at, matched).is_empty());
        let ready = outbox.ready_at(match_at + FIRST_REPLY_DELAY, matched);
        assert_eq!(ready, vec![(request(1, 1), "a")]);
    }

    #[test]
    fn a_reply_waits_for_its_clients_reader_and_others_pass_it() {
        let t0 = long_ago() + Duration::from_secs(1);
        let mut outbox = Outbox::new(TOPIC);
        outbox.push(request(1, 1), "late client", t0);
        outbox.push(request(2, 1), "matched client", t0);
        outbox.push(request(1, 2), "late client again", t0);
        let client_2 =
            |topic: &str, id: RmwRequestId| all_matched(topic, id).filter(|r| r.0 == reader(2));
        let first = outbox.ready_at(t0 + Duration::from_secs(1), client_2);
        assert_eq!(first, vec![(request(2, 1), "matched client")]);
        // Client 1's reader matches: its replies go out in the order of the requests.
        let later = outbox.ready_at(t0 + Duration::from_secs(2), all_matched);
        assert_eq!(
            later,
            vec![
                (request(1, 1), "late client"),
                (request(1, 2), "late client again")
            ]
        );
        assert!(outbox.ready_at(t0 + HOLD * 2, all_matched).is_empty());
    }

    #[test]
    fn a_reply_is_written_anyway_after_the_hold() {
        let t0 = Instant::now();
        let mut outbox = Outbox::new(TOPIC);
        outbox.push(request(1, 1), "a", t0);
        let never = |_: &str, _| None;
        assert!(outbox
            .ready_at(t0 + HOLD - Duration::from_millis(1), never)
            .is_empty());
        assert_eq!(
            outbox.ready_at(t0 + HOLD, never),
            vec![(request(1, 1), "a")]
        );
    }
}

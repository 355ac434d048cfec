//! Service servers in the request/reply mapping of `rmw_cyclonedds_cpp`, shared by the
//! simulator-control services ([`crate::control`]) and the parameter services
//! ([`crate::params`]).

use ros2_client::dds::{Node as RosNode, Server, ServiceMapping};
use ros2_client::{Message, Name, QosProfile, ServiceTypeName};

/// The server of service `base/service` of type `package/srv/ty`, in the request/reply
/// mapping of `rmw_cyclonedds_cpp` (a header of the client's GUID and a sequence number
/// before the request or reply).
///
/// # Errors
///
/// A bad service name, or DDS could not create the server.
pub(crate) fn server<Req, Resp>(
    node: &mut RosNode,
    base: &str,
    service: &str,
    package: &str,
    ty: &str,
    qos: &QosProfile,
) -> Result<Server<Req, Resp>, String>
where
    Req: Message + Clone + 'static,
    Resp: Message + 'static,
{
    let name = Name::new(base, service).map_err(|e| format!("service {base}/{service}: {e:?}"))?;
    node.create_server(
        ServiceMapping::Cyclone,
        &name,
        &ServiceTypeName::new(package, ty),
        qos.clone(),
        qos.clone(),
    )
    .map_err(|e| format!("cannot serve {base}/{service}: {e:?}"))
}

#pragma once
// Typed failures of the qi client, all BridgeError subclasses so the app catches one base type.
//
// Each message names where it happened (URL, service.method) and why, in words a user can act
// on: "cannot reach tcp://10.0.0.5:9559: Connection refused", "wrong user or password for
// tcps://...: Authentication failed: ...", "ALMotion.move: no reply within 3000 ms".

#include "naoqi_bridge/robot_bridge.hpp"

namespace pepper::naoqi_bridge::qi {

/// Host unreachable, name not resolved, connection refused or timed out.
class ConnectError : public BridgeError {
 public:
  using BridgeError::BridgeError;
};
/// TLS handshake failed or the certificate did not match the pinned fingerprint.
class TlsError : public BridgeError {
 public:
  using BridgeError::BridgeError;
};
/// The robot refused the user/password (or the authentication exchange went wrong).
class AuthenticationError : public BridgeError {
 public:
  using BridgeError::BridgeError;
};
/// The service directory does not know the service.
class ServiceNotFound : public BridgeError {
 public:
  using BridgeError::BridgeError;
};
/// The service has no method with that name and parameter signature.
class MethodNotFound : public BridgeError {
 public:
  using BridgeError::BridgeError;
};
/// The remote method answered with an Error message (text included).
class RemoteCallError : public BridgeError {
 public:
  using BridgeError::BridgeError;
};
/// No reply within the call timeout.
class CallTimeout : public BridgeError {
 public:
  using BridgeError::BridgeError;
};
/// The connection is closed or was lost.
class ConnectionLost : public BridgeError {
 public:
  using BridgeError::BridgeError;
};
/// The peer sent a malformed message; the connection was closed.
class ProtocolViolation : public BridgeError {
 public:
  using BridgeError::BridgeError;
};

}  // namespace pepper::naoqi_bridge::qi

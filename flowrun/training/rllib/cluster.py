"""Where RLlib runs: an existing Ray cluster (``--ray-address`` / ``RAY_ADDRESS``) or a local
Ray instance that starts and stops with the run.

An address is checked with a plain TCP connection (a few seconds at most) before Ray is asked
to attach, so an unreachable cluster is a clear error, not a hang.
"""

from __future__ import annotations

import logging
import os
import socket
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from flowrun.errors import TrainingError
from flowrun.training.rllib.deps import require_ray

log = logging.getLogger(__name__)

#: The environment variable Ray itself reads for the cluster address.
RAY_ADDRESS_ENV = "RAY_ADDRESS"
#: Seconds the reachability check of an address waits.
CONNECT_TIMEOUT_S = 5.0
#: Ports Ray listens on when an address names none: the GCS (``ray start --head``) and the
#: Ray Client server (``ray://``).
GCS_PORT, CLIENT_PORT = 6379, 10001


@dataclass(frozen=True)
class RaySession:
    """The Ray instance a run uses.

    Attributes:
        address: the cluster address attached to, ``local`` for a Ray started by this run,
            ``existing`` when Ray was already initialised in this process.
        cpus: logical CPUs of the cluster (all nodes).
    """

    address: str
    cpus: float


def resolve_address(address: str | None) -> str | None:
    """The cluster address: ``address`` if given, else ``$RAY_ADDRESS``, else ``None`` (local)."""
    chosen = address if address else os.environ.get(RAY_ADDRESS_ENV, "")
    chosen = chosen.strip()
    return chosen or None


def host_port(address: str) -> tuple[str, int]:
    """``(host, port)`` of a Ray address (``host:port``, ``ray://host:port``, ``host``).

    Raises:
        TrainingError: the port is not a number.
    """
    rest = address
    default = GCS_PORT
    if "://" in rest:
        scheme, _, rest = rest.partition("://")
        default = CLIENT_PORT if scheme == "ray" else GCS_PORT
    rest = rest.split("/", 1)[0]
    host, sep, port = rest.rpartition(":")
    if not sep:
        return rest, default
    if not port.isdigit():
        raise TrainingError(f"Ray address '{address}': the port '{port}' is not a number")
    return host.strip("[]"), int(port)


def check_reachable(address: str, timeout: float = CONNECT_TIMEOUT_S) -> None:
    """Fail fast when nothing listens at ``address`` (``auto`` is left to Ray).

    Raises:
        TrainingError: no connection within ``timeout`` seconds.
    """
    if address in ("auto", "local"):
        return
    host, port = host_port(address)
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except OSError as err:
        reason = err.strerror or type(err).__name__
        raise TrainingError(
            f"cannot reach the Ray cluster at {address} ({host}:{port}: {reason}); start it "
            "there with `ray start --head`, or fix --ray-address / RAY_ADDRESS"
        ) from None


def send_token_if_available() -> None:
    """Authenticate to the cluster with this machine's Ray token, if it has one.

    Ray 2.60's ``ray start --head`` enables token authentication, but a driver attaching with
    ``ray.init(address=...)`` sends its token (``RAY_AUTH_TOKEN``, ``RAY_AUTH_TOKEN_PATH`` or
    ``~/.ray/auth_token``) only in token mode (measured: refused without it; a cluster
    without authentication accepts a token-mode driver too). Ray's own helper turns token
    mode on, only when ``RAY_AUTH_MODE`` is unset and a token exists, the way ``ray.init()``
    does for a local cluster.
    """
    try:
        from ray._private.authentication.authentication_token_setup import (
            maybe_enable_token_auth_if_token_available,
        )
    except ImportError:  # another Ray release: RAY_AUTH_MODE=token does the same
        return
    maybe_enable_token_auth_if_token_available(warn_if_disabled=False)


@contextmanager
def ray_session(
    address: str | None = None, purpose: str = "train.backend: rllib", rllib: bool = True
) -> Iterator[RaySession]:
    """Attach to a Ray cluster, or start a local Ray sized to this machine, for a block.

    Ray already initialised in this process (e.g. by a test or a notebook) is used as it is
    and left running. Otherwise a local instance (one logical CPU per core) or the attached
    cluster is shut down / disconnected at the end of the block.

    Args:
        address: the cluster address; ``None`` reads ``RAY_ADDRESS`` and without it starts a
            local instance.
        purpose: what needs Ray, for the error of a missing extra.
        rllib: whether RLlib is needed (``flowrun sweep`` on Ray needs Ray core only).

    Raises:
        TrainingError: the rllib extra is missing, or the cluster cannot be reached.
    """
    ray = require_ray(purpose, rllib)
    if ray.is_initialized():
        yield RaySession("existing", float(ray.cluster_resources().get("CPU", 1.0)))
        return
    chosen = resolve_address(address)
    if chosen is None:
        ray.init(
            address="local",  # a new instance, even where `ray start` runs a cluster
            num_cpus=os.cpu_count() or 1,
            include_dashboard=False,
            logging_level=logging.WARNING,
        )
        name = "local"
    else:
        check_reachable(chosen)
        send_token_if_available()
        try:
            ray.init(address=chosen, logging_level=logging.WARNING)
        except (ConnectionError, RuntimeError, ValueError) as err:
            text = str(err).strip()
            first = text.splitlines()[0] if text else type(err).__name__
            raise TrainingError(
                f"cannot attach to the Ray cluster at {chosen}: {first} (a cluster started "
                "with token authentication needs its token here: RAY_AUTH_TOKEN, or "
                "`ray get-auth-token` on the head node saved to ~/.ray/auth_token)"
            ) from None
        name = chosen
    try:
        cpus = float(ray.cluster_resources().get("CPU", 1.0))
        log.info("Ray %s: %.0f CPUs", name, cpus)
        yield RaySession(name, cpus)
    finally:
        ray.shutdown()

"""``asbuilt simulate-device --scene SCENE [--ptu-protocol flir|pelco-d] [--lrf-protocol
dimetix|ldm|lw20] [noise options]``.

Runs a simulated pan-tilt head (FLIR/DP, or Pelco-D at ``--ptu-address``) and a simulated range
finder (Dimetix DLS, Jenoptik LDM or LightWare LW20) on two pseudo-terminals, backed by a scene description or an exported model (ray cast
exactly), and prints the two /dev/pts paths on standard output::

    ptu /dev/pts/3
    lrf /dev/pts/4

then serves until Ctrl-C. Point ``asbuilt scan --ptu /dev/pts/3 --lrf /dev/pts/4`` at them to
exercise the real drivers over a tty (a pseudo-terminal takes 7E1 or 8N1 alike and passes the
bytes through unchanged, so ``--lrf-8n1`` is optional).
"""

from __future__ import annotations

import argparse

__all__ = ["register", "run"]


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``simulate-device`` subcommand to ``subparsers``."""
    parser = subparsers.add_parser(
        "simulate-device",
        help="serve a simulated pan-tilt unit and range finder on pseudo-terminals",
        description="Simulate a FLIR/DP pan-tilt unit and a laser range finder over two "
        "pseudo-terminals, measuring a scene by exact ray casting; prints the tty paths.",
        epilog="Example: asbuilt simulate-device --scene site.scene.json --range-sigma 0.002",
    )
    parser.add_argument(
        "--scene",
        required=True,
        metavar="FILE",
        help="scene description (.json) or exported mesh (.stl, .glb, .obj, .ply)",
    )
    parser.add_argument("--lrf-protocol", choices=("dimetix", "ldm", "lw20"), default="dimetix")
    parser.add_argument("--ptu-protocol", choices=("flir", "pelco-d"), default="flir")
    parser.add_argument("--ptu-address", type=int, default=1, help="Pelco-D address 1-255 (1)")
    parser.add_argument("--station", help="scene station the rig stands at (default: the first)")
    parser.add_argument("--device-id", type=int, default=0, help="Dimetix device id 0-9 (0)")
    parser.add_argument(
        "--calibration",
        metavar="FILE",
        help="the rig's TRUE calibration (default: ideal, at the scene's station)",
    )
    parser.add_argument("--range-sigma", type=float, help="range noise, metres")
    parser.add_argument("--angle-sigma-deg", type=float, help="pointing noise, degrees")
    parser.add_argument("--dropout", type=float, help="probability of a weak-signal dropout")
    parser.add_argument(
        "--divergence-mrad", type=float, help="beam half-angle for mixed edge returns, milliradians"
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed (0)")
    parser.add_argument(
        "--speed",
        type=float,
        default=0.0,
        help="head speed, positions per second (0: moves are instant)",
    )
    parser.set_defaults(handler=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Serve until Ctrl-C; return 0."""
    import math
    import signal
    import sys
    import threading

    from asbuilt.drivers.calibration import load_calibration
    from asbuilt.drivers.pty_sim import PtyServer
    from asbuilt.drivers.simrig import SimNoise, SimulatedRig, load_world, station_defaults
    from asbuilt.errors import DeviceError

    if not 0 <= args.device_id <= 9:
        raise DeviceError(
            f"simulate-device: --device-id must be a Dimetix device id 0-9, not {args.device_id}"
        )
    if not 1 <= args.ptu_address <= 255:
        raise DeviceError(
            f"simulate-device: --ptu-address must be a Pelco-D address 1-255, not {args.ptu_address}"
        )
    world = load_world(args.scene)
    calibration, noise = station_defaults(world, args.station)
    if args.calibration:
        calibration = load_calibration(args.calibration)
    if args.range_sigma is not None:
        noise["range_sigma"] = args.range_sigma
    if args.angle_sigma_deg is not None:
        noise["angle_sigma"] = math.radians(args.angle_sigma_deg)
    if args.dropout is not None:
        noise["dropout"] = args.dropout
    if args.divergence_mrad is not None:
        noise["divergence"] = args.divergence_mrad * 1e-3
    try:
        sim_noise = SimNoise(seed=args.seed, **noise)
        rig = SimulatedRig(world, calibration, sim_noise, speed=args.speed)
    except ValueError as exc:
        raise DeviceError(f"simulate-device: {exc}") from None
    if threading.current_thread() is threading.main_thread():
        # Ctrl-C (SIGINT) stops the server even when it was started with SIGINT ignored (a
        # background job of a non-interactive shell inherits that), where Python would keep
        # ignoring it and the server would never stop.
        signal.signal(signal.SIGINT, signal.default_int_handler)
    server = PtyServer(
        rig,
        args.lrf_protocol,
        args.device_id,
        ptu_protocol=args.ptu_protocol,
        ptu_address=args.ptu_address,
    ).start()
    try:
        print(f"ptu {server.ptu_path}", flush=True)
        print(f"lrf {server.lrf_path}", flush=True)
        print("serving; Ctrl-C to stop", file=sys.stderr, flush=True)
        stop = threading.Event()
        while not stop.wait(0.5):
            if server.error is not None:
                raise DeviceError(f"simulator stopped: {server.error}")
    except KeyboardInterrupt:
        print("stopped", file=sys.stderr)
    finally:
        server.stop()
    return 0

"""Link security commands: `wrangler keygen` (a key file) and `wrangler provision` (into the device, over USB)."""

from __future__ import annotations

import sys

import click

from robowrangler.cli.context import CliContext, pass_context
from robowrangler.errors import InvalidArgument
from robowrangler.link_security import generate_key, read_key_file, write_key_file
from robowrangler.protocol.generated import PARAMS_BY_NAME
from robowrangler.provisioning import Provisioner
from robowrangler.transport_serial import SerialTransport


@click.command()
@click.option("--out", "out_path", default=None, metavar="PATH",
              help="Where to write it [default: --key-file, $ROBOWRANGLER_KEY_FILE or ~/.config/robowrangler/link.key].")
@click.option("--force", is_flag=True, help="Replace an existing key file (the device must then be provisioned again).")
@pass_context
def keygen(ctx: CliContext, out_path: str | None, force: bool) -> None:
    """Create a new random 128-bit link key in a file only you can read (mode 0600). The key is never printed."""
    path = write_key_file(out_path or ctx.resolved_key_file(), generate_key(), force=force)
    ctx.result({"command": "keygen", "key_file": str(path)},
               f"key written to {path}; provision the device with it: wrangler provision --port PORT")


def _parse_param(text: str) -> tuple[str, float]:
    name, sep, value = text.partition("=")
    if not sep or name not in PARAMS_BY_NAME:
        raise InvalidArgument("--param", "NAME=VALUE with a known parameter name", text)
    try:
        return name, float(value)
    except ValueError:
        raise InvalidArgument("--param", "NAME=VALUE with a number", text) from None


@click.command()
@click.option("--port", required=True, metavar="PORT", help="The device's USB serial port (/dev/ttyACM0, COM3, ...).")
@click.option("--baud", type=int, default=115200, show_default=True, help="Serial speed.")
@click.option("--no-key", is_flag=True, help="Do not write the key (only WiFi / parameters).")
@click.option("--ssid", default=None, help="WiFi network name.")
@click.option("--password-stdin", is_flag=True, help="Read the WiFi password from the first line of stdin "
              "(never from the command line, where other users can see it).")
@click.option("--param", "params", multiple=True, metavar="NAME=VALUE", help="A parameter to store (repeatable).")
@click.option("--status", "status_only", is_flag=True, help="Only read what is stored.")
@pass_context
def provision(ctx: CliContext, port: str, baud: int, no_key: bool, ssid: str | None, password_stdin: bool,
              params: tuple[str, ...], status_only: bool) -> None:
    """Write the link key (from --key-file), WiFi credentials and parameters into the device over USB serial.

    The device must be DISARMED. Everything is written to flash as one record with a CRC; the key takes
    effect at once and is never sent over WiFi."""
    parsed = dict(_parse_param(p) for p in params)
    password = sys.stdin.readline().rstrip("\n") if password_stdin else None
    key = None if (no_key or status_only) else read_key_file(ctx.resolved_key_file())
    url = f"serial://{port}?baud={baud}"
    transport = SerialTransport(port, baud=baud, url=url)
    try:
        prov = Provisioner(transport, url=url, timeout_s=ctx.timeout_s)
        status = prov.status() if status_only else prov.provision(key=key, wifi_ssid=ssid, wifi_password=password,
                                                                    params=parsed)
    finally:
        transport.close()
    ctx.result({"command": "provision", "key_set": status.key_set, "wifi_ssid": status.wifi_ssid,
                "password_set": status.password_set, "boot_counter": status.boot_counter, "commits": status.commits,
                "dirty": status.dirty},
               f"provisioned: key {'set' if status.key_set else 'NOT set'}, WiFi '{status.wifi_ssid}' "
               f"(password {'set' if status.password_set else 'not set'}), boot counter {status.boot_counter}, "
               f"{status.commits} writes")

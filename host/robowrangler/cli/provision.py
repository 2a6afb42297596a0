"""Provisioning over USB serial: provision status | provision set.

The link key and the WiFi password are read from files (never from the command line, where shell
history and process listings would keep them) and are never printed.
"""

from __future__ import annotations

import os
import secrets

import click

from robowrangler.cli.context import CliContext, pass_context, read_key_file
from robowrangler.errors import InvalidArgument
from robowrangler.protocol.generated import KEY_LEN
from robowrangler.telemetry import ProvisionStatus


def _human(status: ProvisionStatus) -> str:
    return "\n".join([
        f"link key       {'set' if status.key_set else 'NOT SET (no command over WiFi)'}",
        f"wifi ssid      {status.wifi_ssid or '-'}",
        f"wifi password  {'set' if status.password_set else 'not set'}",
        f"boot counter   {status.boot_counter} (boots since the last commit; session id = epoch + this)",
        f"flash commits  {status.commits}",
        f"config version {status.config_version}",
        f"uncommitted    {'yes' if status.dirty else 'no'}",
    ])


def generate_key_file(path: str, *, argument: str) -> bytes:
    """A new random link key written to path as hex (mode 0600); refuses to overwrite a file.

    Missing parent folders are created (mode 0700: ~/.config/robowrangler/ on a fresh HOME). argument
    names what the user typed (PATH of keygen, --generate-key of provision set) in errors.
    """
    key = secrets.token_bytes(KEY_LEN)
    parent = os.path.dirname(os.path.abspath(path))
    try:
        os.makedirs(parent, mode=0o700, exist_ok=True)
    except OSError as err:
        raise InvalidArgument(argument, "a path whose folder exists or can be created",
                              f"{path} ({parent}: {err.strerror})") from None
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except FileExistsError:
        raise InvalidArgument(argument, "a path that does not exist yet (a key is never overwritten)",
                              path) from None
    except OSError as err:
        raise InvalidArgument(argument, "a writable path", f"{path} ({err.strerror})") from None
    with os.fdopen(fd, "w") as f:
        f.write(key.hex() + "\n")
    return key


@click.group()
@click.option("--port", default=None, metavar="PORT",
              help="The device's USB serial port (/dev/ttyACM0, COM3): short for --url serial://PORT.")
@click.option("--baud", type=int, default=115200, show_default=True, help="Serial speed, with --port.")
@pass_context
def provision(ctx: CliContext, port: str | None, baud: int) -> None:
    """Link key and WiFi credentials, over USB serial only (--port PORT, or --url serial://...)."""
    if port is not None:
        ctx.url = f"serial://{port}?baud={baud}"


@provision.command()
@pass_context
def status(ctx: CliContext) -> None:
    """What the device has stored (the key and the password are never read back)."""
    with ctx.client() as rw:
        st = rw.provision_status()
    ctx.result({"command": "provision status", **st.to_dict()}, _human(st))


@provision.command("set")
@click.option("--generate-key", "generate_key", metavar="PATH",
              help="Create a new random link key, save it to PATH (mode 0600) and store it on the device.")
@click.option("--link-key-file", "link_key_file", metavar="PATH", help="Store the key in PATH (32 hex digits).")
@click.option("--wifi-ssid", default=None, help="WiFi network name.")
@click.option("--wifi-password-file", "password_file", metavar="PATH",
              help="File whose first line is the WiFi password (an empty line: open network).")
@click.option("--no-commit", is_flag=True, help="Stage only; the device writes its flash at the next commit.")
@pass_context
def set_(ctx: CliContext, generate_key: str | None, link_key_file: str | None, wifi_ssid: str | None,
         password_file: str | None, no_commit: bool) -> None:
    """Store a link key and/or WiFi credentials, then write them to flash."""
    if generate_key and link_key_file:
        raise click.UsageError("give --generate-key or --link-key-file, not both")
    if not ctx.url.startswith("serial://"):
        raise InvalidArgument("--url", "a serial:// link: provisioning never travels over WiFi", ctx.url)
    password = None
    if password_file:
        try:
            with open(password_file) as f:
                password = f.readline().rstrip("\r\n")
        except OSError as err:
            raise InvalidArgument("--wifi-password-file", "a readable file", f"{password_file} ({err.strerror})") from None
    key = read_key_file(link_key_file) if link_key_file else None
    if generate_key:
        key = generate_key_file(generate_key, argument="--generate-key")
    try:
        with ctx.client() as rw:
            st = rw.provision(key=key, wifi_ssid=wifi_ssid, wifi_password=password, commit=not no_commit)
    except BaseException:
        if generate_key:
            ctx.note(f"the new key in {generate_key} was NOT stored on the device")
        raise
    if generate_key:
        ctx.note(f"new link key written to {generate_key}: keep it; hosts sign with --key-file {generate_key}")
    ctx.result({"command": "provision set", **st.to_dict()}, _human(st))


@click.command()
@click.argument("path", metavar="PATH")
@pass_context
def keygen(ctx: CliContext, path: str) -> None:
    """Create a new random 128-bit link key in PATH (mode 0600, never overwritten, never printed).

    Provision the device with it over USB (wrangler --url serial://PORT provision set --link-key-file PATH),
    then sign with it (wrangler --key-file PATH ...)."""
    generate_key_file(os.path.expanduser(path), argument="PATH")
    ctx.result({"command": "keygen", "key_file": path}, f"new link key written to {path}")

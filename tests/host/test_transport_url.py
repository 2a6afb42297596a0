"""Link URLs: the two schemes parse, anything else is an InvalidArgument naming what is wrong."""

from __future__ import annotations

import pytest

from robowrangler.client import Client
from robowrangler.errors import InvalidArgument
from robowrangler.transport import SerialUrl, UdpUrl, parse_url


@pytest.mark.parametrize("url, parsed", [
    ("udp://127.0.0.1:14550", UdpUrl("127.0.0.1", 14550)),
    ("udp://robowrangler.local:9000", UdpUrl("robowrangler.local", 9000)),
    ("udp://[::1]:14550", UdpUrl("::1", 14550)),
    ("serial:///dev/ttyACM0?baud=115200", SerialUrl("/dev/ttyACM0", 115200)),
    ("serial:///dev/ttyACM0", SerialUrl("/dev/ttyACM0", 115200)),
    ("serial://loop://?baud=9600", SerialUrl("loop://", 9600)),
    ("serial://COM3?baud=57600", SerialUrl("COM3", 57600)),
])
def test_valid_urls_parse(url: str, parsed: object) -> None:
    assert parse_url(url) == parsed


@pytest.mark.parametrize("url, expected", [
    ("tcp://127.0.0.1:1", "scheme udp:// or serial://"),
    ("127.0.0.1:14550", "scheme udp:// or serial://"),
    ("udp://127.0.0.1", "HOST:PORT"),
    ("udp://:14550", "HOST:PORT"),
    ("udp://127.0.0.1:0", "port in 1..65535"),
    ("udp://127.0.0.1:70000", "port in 1..65535"),
    ("udp://127.0.0.1:abc", "port in 1..65535"),
    ("udp://127.0.0.1:14550/x", "no path or query"),
    ("serial://?baud=115200", "with a port"),
    ("serial:///dev/ttyACM0?baud=fast", "positive integer"),
    ("serial:///dev/ttyACM0?baud=0", "positive integer"),
    ("serial:///dev/ttyACM0?parity=N", "only the query option baud"),
    (14550, "a string"),
])
def test_malformed_urls_name_expected_and_actual(url: object, expected: str) -> None:
    with pytest.raises(InvalidArgument) as info:
        parse_url(url)
    assert info.value.argument == "url" and expected in str(info.value) and repr(url) in str(info.value)


def test_client_refuses_a_bad_url_before_opening_anything() -> None:
    with pytest.raises(InvalidArgument, match="scheme"):
        Client("http://127.0.0.1:80")


@pytest.mark.parametrize("option, value", [("ack_timeout_s", 0.0), ("ack_timeout_s", float("nan")), ("retries", -1),
                                           ("retries", 1.5), ("heartbeat_hz", -10.0), ("first_seq", 70000)])
def test_client_options_are_validated(option: str, value: object) -> None:
    with pytest.raises(InvalidArgument) as info:
        Client("udp://127.0.0.1:14550", **{option: value})
    assert info.value.argument == option


def test_a_missing_serial_port_is_a_link_error_naming_the_url() -> None:
    from robowrangler.errors import LinkError
    from robowrangler.transport import open_transport

    with pytest.raises(LinkError) as info:
        open_transport("serial:///dev/robowrangler-does-not-exist?baud=115200")
    assert str(info.value).startswith("cannot open serial:///dev/robowrangler-does-not-exist?baud=115200: ")
    assert isinstance(info.value, OSError)

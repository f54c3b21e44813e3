"""Options and helpers every command shares: --plugins, Dask TLS files, --param."""
from __future__ import annotations


def _params(items):
    out = {}
    for it in items or []:
        if "=" not in it:
            raise ValueError(f"--param expects KEY=VALUE, got {it!r}")
        k, v = it.split("=", 1)
        if k.strip() == "figure":
            raise ValueError("--param figure=...: use --figure VARIANT.toml (stored with the run)")
        out[k.strip()] = v.strip()
    return out


def _add_plugins_arg(p):
    p.add_argument("--plugins", action="append", default=[], metavar="DIR",
                   help="folder of extra primitives/tasks/figures (repeatable); the only way, "
                        "besides installed entry points, that gpmotion runs code not its own")


def _add_tls_args(p):
    p.add_argument("--tls-ca-file", metavar="PEM", help="Dask TLS: CA certificate (tls:// scheduler)")
    p.add_argument("--tls-cert", metavar="PEM", help="Dask TLS: this client's certificate")
    p.add_argument("--tls-key", metavar="PEM", help="Dask TLS: this client's private key")


def _backend(args) -> dict:
    """This invocation's evaluator settings (TLS files), never recorded in the run."""
    return {k: getattr(args, k) for k in ("tls_ca_file", "tls_cert", "tls_key")
            if getattr(args, k, None)}


def _activate_plugins(args) -> list:
    from ..plugins import activate
    return activate(getattr(args, "plugins", []) or [])

"""``brdfkit serve``: start the browser explorer."""

from __future__ import annotations

import typer


def register(app: typer.Typer) -> None:
    @app.command("serve")
    def serve_cmd(
        port: int = typer.Option(8765, "--port", help="TCP port (0 = pick a free one)"),
        host: str = typer.Option("127.0.0.1", "--host", help="address to bind (default: this machine only)"),
        no_browser: bool = typer.Option(False, "--no-browser", help="do not open a web browser"),
        verbose: bool = typer.Option(False, "--verbose", help="log every request to stderr"),
        allow_host: list[str] = typer.Option(
            [], "--allow-host", metavar="NAME", help="another name the Host header may carry (localhost names and IP literals always work); repeatable"
        ),
    ) -> None:
        """Explore the models in a web browser: sliders, a lit sphere and a polar plot (WebGL 2)."""
        from . import server as web_server

        srv = web_server.make_server(host, port, allowed_hosts=allow_host)
        web_server.Handler.quiet = not verbose
        url = srv.url
        typer.echo(f"brdfkit explorer at {url}  (Ctrl-C to stop)")
        if not no_browser:
            import webbrowser

            try:
                webbrowser.open(url)
            except Exception:  # pragma: no cover - no browser: the URL is printed
                pass
        try:
            srv.serve_forever()
        except KeyboardInterrupt:
            typer.echo("stopped")
        finally:
            srv.server_close()

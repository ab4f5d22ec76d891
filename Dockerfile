# The image of deploy/k8s/sweep-job.yaml: the `ehservo` command line, built
# in release, on a slim Debian with the shipped scenarios and studies.
#   docker build -t your-registry/ehservo:0.1.0 .
# Linted by hadolint in CI (ci/deploy.sh). ci/image.sh builds it (Docker, or
# Podman without a daemon) and runs the manifest's command in it.

FROM rust:1.95-slim-bookworm AS build
WORKDIR /src
COPY . .
RUN cargo build --release --locked -p ehservo

FROM debian:bookworm-slim
COPY --from=build /src/target/release/ehservo /usr/local/bin/ehservo
COPY scenarios /opt/ehservo/scenarios
RUN useradd --uid 10001 --user-group --no-create-home --shell /usr/sbin/nologin ehservo
USER 10001
WORKDIR /opt/ehservo
CMD ["ehservo", "--help"]

# ncchannel in a small runtime image, for soak campaigns across machines (docs/campaigns.md).
# Build: docker build -t ncchannel .
# Run:   docker run --rm ncchannel soak params/soak/stream_resets.toml --blocks 200000 -q
# (CI does not build this image: the CI machine has no container engine.)

# Stage 1: the release binary, built with the toolchain the crate asks for (rust-version).
FROM rust:1.88-slim-bookworm AS build
WORKDIR /src
COPY . .
RUN cargo build --release --locked --bin ncchannel

# Stage 2: the binary and the shipped files it reads, on a slim Debian; no toolchain.
FROM debian:bookworm-slim
RUN useradd --create-home --uid 10001 ncchannel
WORKDIR /home/ncchannel
COPY --from=build /src/target/release/ncchannel /usr/local/bin/ncchannel
COPY --chown=ncchannel params params
COPY --chown=ncchannel nc nc
USER ncchannel
ENTRYPOINT ["ncchannel"]
CMD ["--help"]

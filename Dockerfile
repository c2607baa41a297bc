# The uavtest operator image: `uavtest operator` (kopf) with the package and its dependencies.
#   docker build -t uavtest-operator:0.1.0 .
# The Helm chart runs it as uid 65532 with a read-only root filesystem (HOME and MPLCONFIGDIR in /tmp).
# The e2e suite builds the same image without Docker (tests/cluster/build-runner-image.sh writes
# uavtest-operator:dev: the runner image's layers with this entrypoint, command, user and ports).
FROM python:3.11-slim-bookworm AS build
WORKDIR /src
COPY pyproject.toml README.md* ./
COPY operator ./operator
RUN pip wheel --no-cache-dir --wheel-dir /wheels .

FROM python:3.11-slim-bookworm
ENV PYTHONDONTWRITEBYTECODE=1 PYTHONUNBUFFERED=1 HOME=/tmp MPLCONFIGDIR=/tmp/matplotlib
COPY --from=build /wheels /wheels
RUN pip install --no-cache-dir /wheels/*.whl && rm -rf /wheels \
    && useradd --uid 65532 --user-group --no-create-home --home-dir /tmp uavtest
USER 65532:65532
EXPOSE 8080 8081
ENTRYPOINT ["uavtest"]
CMD ["operator", "--metrics-port=8080", "--liveness-port=8081"]

# A PX4 SITL (SIH) image from a PX4 build you made, for `vehicle.simulator: px4` replicas.
# The build folder is the context; this folder is the named context `uavtest` (BuildKit):
#
#   docker build -f runner-image/px4.Dockerfile --build-context uavtest=runner-image \
#     -t registry.example/px4-sitl:v1.15 /path/to/PX4-Autopilot/build/px4_sitl_default
#
# The same image as runner-image/build-px4-image.sh makes without Docker (see README.md here).
# PX4's binary needs the glibc/libstdc++ of the system it was built on: build PX4 on Debian
# bookworm (or anything with glibc <= 2.36), or change the base to match your build machine.
FROM debian:bookworm-slim
RUN apt-get update \
    && apt-get install -y --no-install-recommends bc \
    && rm -rf /var/lib/apt/lists/* \
    && install -d -m 0777 /var/lib/px4
COPY bin /opt/px4/bin
COPY etc /opt/px4/etc
# parameters.json (every px4_sitl build writes it) tells the entrypoint in which form this build
# takes its home: PX4 <= v1.15 wants degrees * 1e7
COPY parameters.json /opt/px4/
COPY --from=uavtest --chmod=0755 px4-entrypoint.sh /usr/local/bin/px4-sitl
ENV PATH=/opt/px4/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
    PX4_SIM_MODEL=sihsim_quadx
WORKDIR /var/lib/px4
# any uid works: the operator runs it as 65532 with a read-only root and an emptyDir as workingDir
USER 65532:65532
ENTRYPOINT ["/usr/local/bin/px4-sitl"]

/*
 * dpc-cyclone-probe: a Cyclone DDS (C API) participant of the bench, built from
 * idl/dpc/bench.idl by Cyclone's own IDL compiler (idlc). It shows that another DDS
 * implementation, given only the IDL, reads the bench's topics and can change its target.
 *
 *   dpc-cyclone-probe [--domain N] [--bench-id B] [--timeout-s T] [--states K]
 *                     [--request S1,S2,S3 [--request-id ID]]
 *
 * Subscribes to dpc_device_description and dpc_target (TRANSIENT_LOCAL), dpc_waveplate_state
 * and dpc_target_reply, and prints every sample of bench B as one JSON object per line on
 * stdout ("topic" names the topic; non-finite numbers print as null). With --request it
 * publishes a TargetRequest (point target) once the driver's reader has matched.
 *
 * Exits 0 once it has seen the device description, a target, K states and (with --request)
 * the target whose request_id is ours and the driver's reply (or 1 s has passed since that target); 1 on timeout (stderr says what is missing); 2 on bad
 * arguments; 3 if Cyclone refused an entity. The network configuration comes from
 * CYCLONEDDS_URI (tests/interop/cyclonedds-loopback.xml confines it to `lo`).
 */
#define _POSIX_C_SOURCE 200809L  /* clock_gettime */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "dds/dds.h"
#include "bench.h"

static void print_double(double x) {
  if (isfinite(x)) {
    printf("%.17g", x);
  } else {
    printf("null");
  }
}

static void print_doubles(const double *values, uint32_t n) {
  printf("[");
  for (uint32_t i = 0; i < n; ++i) {
    if (i > 0) printf(",");
    print_double(values[i]);
  }
  printf("]");
}

/* JSON string: the bench's strings are bounded IDL strings; escape quotes, backslashes and
 * control characters. */
static void print_string(const char *s) {
  putchar('"');
  for (; *s != '\0'; ++s) {
    const unsigned char c = (unsigned char)*s;
    if (c == '"' || c == '\\') {
      printf("\\%c", c);
    } else if (c < 0x20) {
      printf("\\u%04x", c);
    } else {
      putchar(c);
    }
  }
  putchar('"');
}

static const char *target_kind_name(dpc_msg_TargetKind kind) {
  switch (kind) {
    case dpc_msg_TARGET_POINT: return "TARGET_POINT";
    case dpc_msg_TARGET_SET: return "TARGET_SET";
  }
  return "unknown";
}

static const char *stage_kind_name(dpc_msg_StageKind kind) {
  switch (kind) {
    case dpc_msg_STAGE_FIXED_AXIS: return "STAGE_FIXED_AXIS";
    case dpc_msg_STAGE_ADJUSTABLE_AXIS: return "STAGE_ADJUSTABLE_AXIS";
  }
  return "unknown";
}

static const char *map_kind_name(dpc_msg_ControlMapKind kind) {
  switch (kind) {
    case dpc_msg_MAP_LINEAR: return "MAP_LINEAR";
    case dpc_msg_MAP_POLYNOMIAL: return "MAP_POLYNOMIAL";
    case dpc_msg_MAP_TABLE: return "MAP_TABLE";
  }
  return "unknown";
}

static void print_description(const dpc_msg_DeviceDescription *d) {
  printf("{\"topic\":\"dpc_device_description\",\"bench_id\":");
  print_string(d->bench_id);
  printf(",\"driver_id\":");
  print_string(d->driver_id);
  printf(",\"max_slew_per_s\":");
  print_double(d->max_slew_per_s);
  printf(",\"stages\":[");
  for (uint32_t i = 0; i < d->stages._length; ++i) {
    const dpc_msg_Stage *s = &d->stages._buffer[i];
    if (i > 0) printf(",");
    printf("{\"name\":");
    print_string(s->name);
    printf(",\"kind\":\"%s\",\"axis\":", stage_kind_name(s->kind));
    print_doubles(s->axis, 3);
    printf(",\"map\":{\"kind\":\"%s\",\"rad_per_unit\":", map_kind_name(s->control_map.kind));
    print_double(s->control_map.rad_per_unit);
    printf(",\"offset_rad\":");
    print_double(s->control_map.offset_rad);
    printf("},\"range\":{\"limited\":%s,\"min_phi\":", s->range.limited ? "true" : "false");
    print_double(s->range.min_phi);
    printf(",\"max_phi\":");
    print_double(s->range.max_phi);
    printf("}}");
  }
  printf("]}\n");
}

static void print_target(const dpc_msg_Target *t) {
  printf("{\"topic\":\"dpc_target\",\"bench_id\":");
  print_string(t->bench_id);
  printf(",\"revision\":%" PRIu64 ",\"request_id\":", t->revision);
  print_string(t->request_id);
  printf(",\"kind\":\"%s\",\"point\":", target_kind_name(t->kind));
  print_doubles(t->point, 3);
  printf(",\"normal\":");
  print_doubles(t->normal, 3);
  printf(",\"offset\":");
  print_double(t->offset);
  printf("}\n");
}

static void print_state(const dpc_msg_WaveplateState *s) {
  printf("{\"topic\":\"dpc_waveplate_state\",\"bench_id\":");
  print_string(s->bench_id);
  printf(",\"sequence_number\":%" PRIu64 ",\"answers_sample\":%" PRIu64
         ",\"publish_time_ns\":%" PRId64 ",\"phi_applied\":",
         s->sequence_number, s->answers_sample, s->publish_time_ns);
  print_doubles(s->phi_applied._buffer, s->phi_applied._length);
  printf(",\"saturated\":[");
  for (uint32_t i = 0; i < s->saturated._length; ++i) {
    printf("%s%s", i > 0 ? "," : "", s->saturated._buffer[i] ? "true" : "false");
  }
  printf("],\"mode\":\"%s\",\"reason\":", s->mode == dpc_msg_DRIVER_ACTIVE ? "DRIVER_ACTIVE" : "DRIVER_HOLDING");
  print_string(s->reason);
  printf(",\"obeyed_controller_id\":");
  print_string(s->obeyed_controller_id);
  printf(",\"commands_applied\":%" PRIu64 ",\"commands_rejected\":%" PRIu64 "}\n",
         s->commands_applied, s->commands_rejected);
}

static void print_reply(const dpc_msg_TargetReply *r) {
  printf("{\"topic\":\"dpc_target_reply\",\"bench_id\":");
  print_string(r->bench_id);
  printf(",\"request_id\":");
  print_string(r->request_id);
  printf(",\"accepted\":%s,\"revision\":%" PRIu64 ",\"message\":", r->accepted ? "true" : "false",
         r->revision);
  print_string(r->message);
  printf("}\n");
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void usage(FILE *out) {
  fprintf(out,
          "usage: dpc-cyclone-probe [--domain N] [--bench-id B] [--timeout-s T] [--states K]\n"
          "                         [--request S1,S2,S3 [--request-id ID]]\n"
          "Reads the bench's topics with Cyclone DDS and prints one JSON object per sample;\n"
          "with --request publishes a point TargetRequest. Network: CYCLONEDDS_URI.\n");
}

/* The bench's DDS partition, "dpc.<bench id>" (common/dpc/bus/topics.h). */
static char partition[128];

static dds_entity_t make_reader(dds_entity_t participant, const dds_topic_descriptor_t *descriptor,
                                const char *name, bool transient_local, int32_t depth,
                                bool reliable) {
  const dds_entity_t topic = dds_create_topic(participant, descriptor, name, NULL, NULL);
  if (topic < 0) {
    fprintf(stderr, "dds_create_topic(%s): %s\n", name, dds_strretcode(-topic));
    exit(3);
  }
  dds_qos_t *qos = dds_create_qos();
  /* The bench's QoS (deploy/fastdds/loopback.xml): the periodic topics are best effort. */
  dds_qset_reliability(qos, reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT,
                       DDS_SECS(1));
  dds_qset_durability(qos, transient_local ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, depth);
  dds_qset_partition1(qos, partition);
  const dds_entity_t reader = dds_create_reader(participant, topic, qos, NULL);
  dds_delete_qos(qos);
  if (reader < 0) {
    fprintf(stderr, "dds_create_reader(%s): %s\n", name, dds_strretcode(-reader));
    exit(3);
  }
  return reader;
}

int main(int argc, char **argv) {
  long domain = 0;
  const char *bench_id = "bench1";
  double timeout_s = 20.0;
  long states_wanted = 3;
  bool request = false;
  double request_point[3] = {0, 0, 0};
  const char *request_id = "cyclone-probe";

  for (int i = 1; i < argc; ++i) {
    const char *arg = argv[i];
    const char *value = (i + 1 < argc) ? argv[i + 1] : NULL;
    char *end = NULL;
    if (strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0) {
      usage(stdout);
      return 0;
    }
    if (value == NULL) {
      fprintf(stderr, "%s needs a value\n", arg);
      usage(stderr);
      return 2;
    }
    ++i;
    errno = 0;
    if (strcmp(arg, "--domain") == 0) {
      domain = strtol(value, &end, 10);
      if (*end != '\0' || errno != 0 || domain < 0 || domain > 232) {
        fprintf(stderr, "--domain: bad value '%s'\n", value);
        return 2;
      }
    } else if (strcmp(arg, "--bench-id") == 0) {
      if (strlen(value) == 0 || strlen(value) > 63) {
        fprintf(stderr, "--bench-id: 1 to 63 characters\n");
        return 2;
      }
      bench_id = value;
    } else if (strcmp(arg, "--timeout-s") == 0) {
      timeout_s = strtod(value, &end);
      if (*end != '\0' || !(timeout_s > 0)) {
        fprintf(stderr, "--timeout-s: bad value '%s'\n", value);
        return 2;
      }
    } else if (strcmp(arg, "--states") == 0) {
      states_wanted = strtol(value, &end, 10);
      if (*end != '\0' || errno != 0 || states_wanted < 0) {
        fprintf(stderr, "--states: bad value '%s'\n", value);
        return 2;
      }
    } else if (strcmp(arg, "--request") == 0) {
      if (sscanf(value, "%lf,%lf,%lf", &request_point[0], &request_point[1], &request_point[2]) != 3) {
        fprintf(stderr, "--request: expected S1,S2,S3, got '%s'\n", value);
        return 2;
      }
      request = true;
    } else if (strcmp(arg, "--request-id") == 0) {
      if (strlen(value) == 0 || strlen(value) > 63) {
        fprintf(stderr, "--request-id: 1 to 63 characters\n");
        return 2;
      }
      request_id = value;
    } else {
      fprintf(stderr, "unknown option %s\n", arg);
      usage(stderr);
      return 2;
    }
  }

  snprintf(partition, sizeof partition, "dpc.%s", bench_id);
  const dds_entity_t participant = dds_create_participant((dds_domainid_t)domain, NULL, NULL);
  if (participant < 0) {
    fprintf(stderr, "dds_create_participant(domain %ld): %s (check CYCLONEDDS_URI)\n", domain,
            dds_strretcode(-participant));
    return 3;
  }
  const dds_entity_t descriptions =
      make_reader(participant, &dpc_msg_DeviceDescription_desc, "dpc_device_description", true, 1, true);
  const dds_entity_t targets = make_reader(participant, &dpc_msg_Target_desc, "dpc_target", true, 1, true);
  const dds_entity_t states =
      make_reader(participant, &dpc_msg_WaveplateState_desc, "dpc_waveplate_state", false, 1, false);
  const dds_entity_t replies =
      make_reader(participant, &dpc_msg_TargetReply_desc, "dpc_target_reply", false, 8, true);

  dds_entity_t request_writer = 0;
  if (request) {
    const dds_entity_t topic =
        dds_create_topic(participant, &dpc_msg_TargetRequest_desc, "dpc_target_request", NULL, NULL);
    if (topic < 0) {
      fprintf(stderr, "dds_create_topic(dpc_target_request): %s\n", dds_strretcode(-topic));
      return 3;
    }
    dds_qos_t *qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
    dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 8);
    dds_qset_partition1(qos, partition);
    request_writer = dds_create_writer(participant, topic, qos, NULL);
    dds_delete_qos(qos);
    if (request_writer < 0) {
      fprintf(stderr, "dds_create_writer(dpc_target_request): %s\n", dds_strretcode(-request_writer));
      return 3;
    }
  }

  /* Samples are taken into loaned buffers (Cyclone allocates the sequences). */
  void *samples[1] = {NULL};
  dds_sample_info_t info[1];
  bool have_description = false;
  bool have_target = false;
  bool have_our_target = false;
  bool have_reply = false;
  double our_target_s = 0;
  long states_seen = 0;
  int requests_sent = 0;
  double last_request_s = 0;
  const double start_s = now_s();
  const double deadline_s = start_s + timeout_s;

  for (;;) {
    int32_t n;
    while ((n = dds_take(descriptions, samples, info, 1, 1)) > 0) {
      const dpc_msg_DeviceDescription *d = samples[0];
      if (info[0].valid_data && strcmp(d->bench_id, bench_id) == 0) {
        print_description(d);
        have_description = true;
      }
      dds_return_loan(descriptions, samples, n);
      samples[0] = NULL;
    }
    while ((n = dds_take(targets, samples, info, 1, 1)) > 0) {
      const dpc_msg_Target *t = samples[0];
      if (info[0].valid_data && strcmp(t->bench_id, bench_id) == 0) {
        print_target(t);
        have_target = true;
        if (request && strcmp(t->request_id, request_id) == 0 && !have_our_target) {
          have_our_target = true;
          our_target_s = now_s();
        }
      }
      dds_return_loan(targets, samples, n);
      samples[0] = NULL;
    }
    while ((n = dds_take(states, samples, info, 1, 1)) > 0) {
      const dpc_msg_WaveplateState *s = samples[0];
      if (info[0].valid_data && strcmp(s->bench_id, bench_id) == 0 && states_seen < states_wanted) {
        print_state(s);
        ++states_seen;
      }
      dds_return_loan(states, samples, n);
      samples[0] = NULL;
    }
    while ((n = dds_take(replies, samples, info, 1, 1)) > 0) {
      const dpc_msg_TargetReply *r = samples[0];
      if (info[0].valid_data && strcmp(r->bench_id, bench_id) == 0) {
        print_reply(r);
        if (request && strcmp(r->request_id, request_id) == 0) have_reply = true;
      }
      dds_return_loan(replies, samples, n);
      samples[0] = NULL;
    }
    fflush(stdout);

    const double t = now_s();
    if (request && !have_our_target && !have_reply) {
      /* Send once the driver's request reader has matched; resend (same request id) if neither
       * a reply nor the new target came within 3 s: a VOLATILE sample written just after
       * "matched" can be missed while the other side is still matching us. */
      dds_publication_matched_status_t matched;
      if (dds_get_publication_matched_status(request_writer, &matched) == DDS_RETCODE_OK &&
          matched.current_count > 0 && (requests_sent == 0 || t - last_request_s > 3.0)) {
        dpc_msg_TargetRequest r;
        memset(&r, 0, sizeof r);
        snprintf(r.bench_id, sizeof r.bench_id, "%s", bench_id);
        snprintf(r.request_id, sizeof r.request_id, "%s", request_id);
        r.kind = dpc_msg_TARGET_POINT;
        memcpy(r.point, request_point, sizeof r.point);
        const dds_return_t rc = dds_write(request_writer, &r);
        if (rc != DDS_RETCODE_OK) {
          fprintf(stderr, "dds_write(dpc_target_request): %s\n", dds_strretcode(-rc));
        } else {
          ++requests_sent;
          last_request_s = t;
          fprintf(stderr, "dpc-cyclone-probe: sent TargetRequest %s [%g,%g,%g] after %.3f s\n",
                  request_id, request_point[0], request_point[1], request_point[2], t - start_s);
        }
      }
    }

    /* The reply follows the target: give it up to 1 s once the new target is here. */
    const bool done = have_description && have_target && states_seen >= states_wanted &&
                      (!request || (have_our_target && (have_reply || t - our_target_s > 1.0)));
    if (done) {
      fprintf(stderr, "dpc-cyclone-probe: done after %.3f s\n", now_s() - start_s);
      break;
    }
    if (t > deadline_s) {
      fprintf(stderr,
              "dpc-cyclone-probe: timeout after %.1f s: description %s, target %s, states %ld/%ld%s\n",
              timeout_s, have_description ? "yes" : "no", have_target ? "yes" : "no", states_seen,
              states_wanted,
              request ? (have_our_target ? ", requested target yes"
                                         : (requests_sent ? ", requested target no (sent)"
                                                          : ", requested target no (driver's reader not matched)"))
                      : "");
      dds_delete(participant);
      return 1;
    }
    dds_sleepfor(DDS_MSECS(10));
  }
  dds_delete(participant);
  return 0;
}

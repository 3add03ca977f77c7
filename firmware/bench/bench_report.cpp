#include "bench_report.h"

namespace seqslam::bench {

void print(const char* s) {
  board::console_print(s);
}

void print_u(uint64_t v) {
  board::console_print_u64(v);
}

void print_fixed(uint64_t v, uint64_t d, int digits) {
  uint64_t scale = 1;
  for (int i = 0; i < digits; ++i)
    scale *= 10;
  const uint64_t q = (v * scale + d / 2) / d;
  print_u(q / scale);
  print(".");
  uint64_t frac = q % scale;
  for (uint64_t s = scale / 10; s > 0; s /= 10) {
    print_u(frac / s);
    frac %= s;
  }
}

MemoryReport memory_report() {
  MemoryReport r;
  r.mem = board::memory_usage();
  r.stack_high_water = board::stack_high_water_bytes();
  r.static_ram = r.mem.text_bytes + r.mem.rodata_bytes + r.mem.data_bytes + r.mem.bss_bytes;
  return r;
}

void print_memory(const MemoryReport& r) {
  const board::MemoryUsage& mem = r.mem;
  print("\nRAM (65456-byte region): code ");
  print_u(mem.text_bytes);
  print(" + rodata ");
  print_u(mem.rodata_bytes);
  print(" + data ");
  print_u(mem.data_bytes);
  print(" + bss ");
  print_u(mem.bss_bytes);
  print(" = ");
  print_u(r.static_ram);
  print(" bytes static; stack reserved ");
  print_u(mem.stack_bytes);
  print(", high-water ");
  print_u(r.stack_high_water);
  print(" bytes; region used ");
  print_u(mem.ram_used_bytes);
  print(" of ");
  print_u(mem.ram_capacity_bytes);
  print("\nexternal memory used: ");
  print_u(mem.extmem_used_bytes);
  print(" bytes");
}

void print_memory_json(const MemoryReport& r, const char* external_memory_note) {
  const board::MemoryUsage& mem = r.mem;
  print("\"memory\": {\"text_bytes\": ");
  print_u(mem.text_bytes);
  print(", \"rodata_bytes\": ");
  print_u(mem.rodata_bytes);
  print(", \"data_bytes\": ");
  print_u(mem.data_bytes);
  print(", \"bss_bytes\": ");
  print_u(mem.bss_bytes);
  print(", \"static_ram_bytes\": ");
  print_u(r.static_ram);
  print(", \"stack_reserved_bytes\": ");
  print_u(mem.stack_bytes);
  print(", \"stack_high_water_bytes\": ");
  print_u(r.stack_high_water);
  print(", \"ram_used_bytes\": ");
  print_u(mem.ram_used_bytes);
  print(", \"ram_capacity_bytes\": ");
  print_u(mem.ram_capacity_bytes);
  print(", \"external_memory_bytes\": ");
  print_u(mem.extmem_used_bytes);
  print(", \"external_memory_note\": \"");
  print(external_memory_note);
  print("\"}");
}

void print_json_begin() {
  print("BEGIN_SUMMARY_JSON\n{\n  \"config\": {");
}

void print_json_config_end() {
  print("\"target\": \"rv32imc qemu-virt\", \"counter\": \"minstret with -icount shift=0\"}");
}

void print_json_end() {
  print("\n}\nEND_SUMMARY_JSON\n");
}

}  // namespace seqslam::bench

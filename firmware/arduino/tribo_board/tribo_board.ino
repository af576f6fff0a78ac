// tribo_board.ino: an acquisition board for bayestribo on an Arduino-style board.
//
// The protocol (docs/protocol.md) is done by the portable library tribo_board.c/.h;
// this sketch is the hardware around it: USB serial for the link, two analog inputs
// for the vibrometer's displacement and velocity outputs, a digital output driving
// the electromagnet (through a transistor or a driver, never directly).
//
// Copy ../../tribo_board.c and ../../tribo_board.h into a src/ folder beside this
// file (`make -C firmware arduino` does it): the Arduino IDE compiles a sketch's src/.
//
// The sample clock: on a Teensy (TEENSYDUINO) an IntervalTimer interrupt takes the
// samples, which is what a real run needs (samples at exact times while the main loop
// sends). Elsewhere the main loop takes them when micros() says they are due: good
// for trying the chain on a bench, with some jitter while a frame is being written.
// 20 kS/s of two channels needs a 32-bit board with native USB (Teensy 3/4, Due,
// RP2040...): an 8-bit board's UART at 115 200 bit/s carries about 2.7 kS/s.

#include "src/tribo_board.h"

// ---- The board: adjust to the hardware and to the vibrometer's settings ------------
const int PIN_DISPLACEMENT = A0;
const int PIN_VELOCITY = A1;
const int PIN_MAGNET = 2;
const int ADC_BITS = 12;                 // resolution of analogRead
// The vibrometer outputs at full scale of the inputs (±): these set the scales.
const double DISPLACEMENT_RANGE_M = 2e-3;     // e.g. DD-500 at 2 mm/V, ±1 V into the ADC
const double VELOCITY_RANGE_M_PER_S = 0.5;    // e.g. VD-06 at 0.5 m/s/V
// +1 if the velocity output rises while the displacement increases, else -1: the
// protocol wants velocity = d(displacement)/dt.
const int VELOCITY_SIGN = +1;
const char IDENT[] = "yourlab,tribo-daq,0001,tribo_board-1";
const char LABEL[] = "DD-500 2 mm/V; VD-06 0.5 m/s/V";

static tb_board board;
static volatile bool sampling = false;
static unsigned long period_us = 50;
static unsigned long next_us = 0;
#if defined(TEENSYDUINO)
static IntervalTimer sample_timer;
#endif

// ---- The hardware behind the library ------------------------------------------------
static void io_write(void *, const uint8_t *data, size_t n) { Serial.write(data, n); }

static void io_frame_done(void *, uint8_t type, uint32_t) {
  if (type != TB_DATA) Serial.flush();  // answers go out at once
}

static int io_set_rate(void *, double rate_hz, double *actual) {
  double period = 1e6 / rate_hz;
  if (period < 5.0 || period > 1e6) return 1;  // what micros() and the ADC can do
  period_us = (unsigned long)(period + 0.5);
  *actual = 1e6 / period_us;  // the rate really made, reported in the HEADER
  return 0;
}

static int16_t to_count(int raw) {
  // 0 … 2^bits - 1 around mid-scale, to a signed 16-bit count.
  long centred = (long)raw - (1L << (ADC_BITS - 1));
  long count = centred << (16 - ADC_BITS);
  if (count > 32767) count = 32767;
  if (count < -32768) count = -32768;
  return (int16_t)count;
}

static void take_sample() {
  int16_t d = to_count(analogRead(PIN_DISPLACEMENT));
  int16_t v = to_count(analogRead(PIN_VELOCITY));
  if (VELOCITY_SIGN < 0) v = (v == -32768) ? 32767 : (int16_t)-v;
  tb_push_sample(&board, d, v);
}

static void io_sampling(void *, int on) {
  sampling = on;
#if defined(TEENSYDUINO)
  if (on) sample_timer.begin(take_sample, (float)period_us);
  else sample_timer.end();
#else
  next_us = micros();
#endif
}

static void io_magnet(void *, int on) { digitalWrite(PIN_MAGNET, on ? HIGH : LOW); }

static void io_critical(void *, int enter) {
  if (enter) noInterrupts();
  else interrupts();
}

void setup() {
  pinMode(PIN_MAGNET, OUTPUT);
  digitalWrite(PIN_MAGNET, LOW);
#if defined(TEENSYDUINO) || defined(ARDUINO_ARCH_SAM) || defined(ARDUINO_ARCH_SAMD) || \
    defined(ARDUINO_ARCH_RP2040) || defined(ESP32)
  analogReadResolution(ADC_BITS);  // on an AVR board, set ADC_BITS = 10 instead
#endif
  Serial.begin(921600);  // ignored by native USB; the rate of a UART bridge
  tb_io io = {};
  io.write = io_write;
  io.frame_done = io_frame_done;
  io.set_rate = io_set_rate;
  io.sampling = io_sampling;
  io.magnet = io_magnet;
  io.critical = io_critical;
  tb_init(&board, &io, IDENT);
  board.disp_range_m = DISPLACEMENT_RANGE_M;
  board.vel_range_m_per_s = VELOCITY_RANGE_M_PER_S;
  board.disp_scale_m = DISPLACEMENT_RANGE_M / 32768.0;
  board.vel_scale_m_per_s = VELOCITY_RANGE_M_PER_S / 32768.0;
  strncpy(board.label, LABEL, TB_MAX_LABEL);
  board.link_bps = 0;  // native USB; 921600 on a UART bridge (RATE x SPF is then checked)
}

void loop() {
  while (Serial.available() > 0) tb_rx_byte(&board, (uint8_t)Serial.read());
#if !defined(TEENSYDUINO)
  if (sampling && (long)(micros() - next_us) >= 0) {
    next_us += period_us;
    take_sample();
  }
#endif
  tb_poll(&board);
}

// The serial vectors of one CVODE(S) integrator, from a pool.  N_VClone of a pool vector takes a
// header from a slab and its n doubles from a data slab allocated in large chunks and not touched
// until the vector is; N_VDestroy puts it back for the next clone.  SUNDIALS' own serial clone makes
// four allocations and copies the operation table (~0.5 µs), and CVODES' adjoint clones two vectors
// for every step of a checkpoint interval up front (CVodeAdjInit's Nd): 1000 steps per interval cost
// ~1 ms before the first step, more than the whole forward run of a 7-DOF arm over 0.5 s.
//
// The vectors are serial vectors to everything that reads them (NV_CONTENT_S's layout, the serial
// operations with nvector_ops.hpp's compiled loops installed, fused and vector-array operations on);
// only clone, empty clone and destroy are the pool's.  The pool outlives every vector it made: the
// owner declares it before anything that holds one (cvode.hpp).
#pragma once

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <memory>
#include <vector>

namespace soadyn::nvector_ops {

class VectorPool {
 public:
  VectorPool();
  ~VectorPool();
  VectorPool(const VectorPool&) = delete;
  VectorPool& operator=(const VectorPool&) = delete;

  // a vector of length n (its entries unset); N_VClone of it, or of its clones, is a pool vector too
  N_Vector make(sunindextype n, SUNContext ctx);
  // vectors made (by make or a clone) and not yet destroyed
  long live() const { return live_; }
  // doubles reserved for the vectors' entries so far (touched or not)
  long reserved() const { return reserved_; }

 private:
  struct Node;
  struct Shelf {  // the vectors of one length
    sunindextype n = 0;
    Node* free = nullptr;
    double* next = nullptr;  // the next unused slot of the current data chunk
    long left = 0;           // slots left there
    long chunk = 64;         // the next chunk's slots (doubling to 8192)
  };

  Node* take(int shelf, SUNContext ctx, bool with_data);
  static N_Vector clone(N_Vector w);
  static N_Vector clone_empty(N_Vector w);
  static void destroy(N_Vector v);

  _generic_N_Vector_Ops ops_{};
  bool ops_ready_ = false;
  std::vector<Shelf> shelves_;
  std::vector<std::unique_ptr<Node[]>> node_chunks_;
  Node* next_node_ = nullptr;
  long nodes_left_ = 0;
  std::vector<std::unique_ptr<double[]>> data_chunks_;
  long live_ = 0, reserved_ = 0;
};

}  // namespace soadyn::nvector_ops

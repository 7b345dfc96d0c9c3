// The pool of serial vectors (nvector_pool.hpp).
#include "nvector_pool.hpp"

#include "nvector_ops.hpp"

#include <algorithm>
#include <cstddef>
#include <new>
#include <type_traits>

namespace soadyn::nvector_ops {

// a vector, its serial content (the layout NV_CONTENT_S reads, first) and the pool's bookkeeping;
// the N_Vector is the first member, so the N_Vector a clone returns is the node's address
struct VectorPool::Node {
  _generic_N_Vector v;
  _N_VectorContent_Serial content;
  VectorPool* pool;
  Node* next;    // in its shelf's free list
  double* slot;  // its n doubles, kept while it is free
  int shelf;
};
static_assert(std::is_standard_layout_v<_generic_N_Vector>);

VectorPool::VectorPool() = default;
VectorPool::~VectorPool() = default;

N_Vector VectorPool::make(sunindextype n, SUNContext ctx) {
  if (!ops_ready_) {
    // the serial table with the compiled loops and the fused operations, then the pool's three
    N_Vector t = new_vector(1, ctx);
    if (!t) return nullptr;
    ops_ = *t->ops;
    N_VDestroy(t);
    ops_.nvclone = &VectorPool::clone;
    ops_.nvcloneempty = &VectorPool::clone_empty;
    ops_.nvdestroy = &VectorPool::destroy;
    ops_ready_ = true;
  }
  auto it = std::find_if(shelves_.begin(), shelves_.end(), [&](const Shelf& s) { return s.n == n; });
  if (it == shelves_.end()) {
    shelves_.push_back(Shelf{});
    shelves_.back().n = n;
    it = shelves_.end() - 1;
  }
  Node* node = take(int(it - shelves_.begin()), ctx, true);
  return node ? &node->v : nullptr;
}

// a free node of the shelf, or a new one with the next slot of the shelf's data chunk
VectorPool::Node* VectorPool::take(int s, SUNContext ctx, bool with_data) {
  Shelf& shelf = shelves_[size_t(s)];
  Node* node = shelf.free;
  if (node) {
    shelf.free = node->next;
  } else {
    try {
      if (nodes_left_ == 0) {
        constexpr long kNodes = 512;
        node_chunks_.emplace_back(new Node[kNodes]);
        next_node_ = node_chunks_.back().get();
        nodes_left_ = kNodes;
      }
      if (shelf.left == 0) {
        // uninitialized: a large chunk is mapped by the allocator and its pages are touched only
        // by the vectors that are written
        data_chunks_.emplace_back(new double[size_t(shelf.chunk * std::max<sunindextype>(shelf.n, 1))]);
        shelf.next = data_chunks_.back().get();
        shelf.left = shelf.chunk;
        reserved_ += shelf.chunk * shelf.n;
        shelf.chunk = std::min(2 * shelf.chunk, 8192L);
      }
    } catch (const std::bad_alloc&) {
      return nullptr;  // SUNDIALS' clone reports NULL
    }
    node = next_node_++;
    --nodes_left_;
    node->pool = this;
    node->shelf = s;
    node->slot = shelf.next;
    shelf.next += shelf.n;
    --shelf.left;
  }
  node->v.content = &node->content;
  node->v.ops = &ops_;
  node->v.sunctx = ctx;
  node->content.length = shelf.n;
  node->content.own_data = SUNFALSE;
  node->content.data = with_data ? node->slot : nullptr;
  node->next = nullptr;
  ++live_;
  return node;
}

N_Vector VectorPool::clone(N_Vector w) {
  Node* from = reinterpret_cast<Node*>(w);
  Node* node = from->pool->take(from->shelf, w->sunctx, true);
  return node ? &node->v : nullptr;
}

N_Vector VectorPool::clone_empty(N_Vector w) {
  Node* from = reinterpret_cast<Node*>(w);
  Node* node = from->pool->take(from->shelf, w->sunctx, false);
  return node ? &node->v : nullptr;
}

void VectorPool::destroy(N_Vector v) {
  Node* node = reinterpret_cast<Node*>(v);
  VectorPool* pool = node->pool;
  Shelf& shelf = pool->shelves_[size_t(node->shelf)];
  node->next = shelf.free;
  shelf.free = node;
  --pool->live_;
}

}  // namespace soadyn::nvector_ops

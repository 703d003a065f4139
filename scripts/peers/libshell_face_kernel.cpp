// The face kernel of libshell (Chen, Sastry, van Rees & Vouga; github.com/evouga/libshell),
// timed like shellsim's `cargo bench --bench kernels -- kernel/midedge_sin`: energy, gradient
// and Hessian of one face's St Venant-Kirchhoff stretching (9 DOFs) and mid-edge-angle (sin)
// bending (21 DOFs), no Hessian projection, no assembly; best of REPS passes over every face of
// a jittered, curved n x n grid (2 n^2 faces), in microseconds per face.
//
// Build against a libshell checkout (its include/ and src/) and Eigen 3 (Debian:
// libeigen3-dev):
//
//     g++ -O3 -march=native -DNDEBUG -std=c++17 -I $LIBSHELL/include -I /usr/include/eigen3 \
//         libshell_face_kernel.cpp $LIBSHELL/src/ElasticShell.cpp \
//         $LIBSHELL/src/GeometryDerivatives.cpp $LIBSHELL/src/MeshConnectivity.cpp \
//         $LIBSHELL/src/MaterialModel/*.cpp $LIBSHELL/src/SecondFundamentalForm/*.cpp \
//         -o libshell_face_kernel
//     ./libshell_face_kernel 50 30
#include "ElasticShell.h"
#include "MeshConnectivity.h"
#include "RestState.h"
#include "StVKMaterial.h"
#include "MidedgeAngleSinFormulation.h"
#include <chrono>
#include <cstdio>
#include <random>
using namespace LibShell;
int main(int argc, char** argv) {
    int n = argc > 1 ? atoi(argv[1]) : 50;
    int reps = argc > 2 ? atoi(argv[2]) : 20;
    int nv = (n + 1) * (n + 1);
    Eigen::MatrixXd X(nv, 3), P(nv, 3);
    std::mt19937 rng(3); std::uniform_real_distribution<double> u(-1, 1);
    double h = 1.0 / n;
    for (int j = 0; j <= n; j++) for (int i = 0; i <= n; i++) {
        int v = j * (n + 1) + i;
        double x = i * h + ((i > 0 && i < n) ? 0.2 * h * u(rng) : 0), y = j * h + ((j > 0 && j < n) ? 0.2 * h * u(rng) : 0);
        X.row(v) << x, y, 0;
        P.row(v) << 1.03 * x + 0.02 * y, 0.98 * y, 0.2 * (x * x - 0.5 * y * y);
    }
    Eigen::MatrixXi F(2 * n * n, 3);
    int f = 0;
    for (int j = 0; j < n; j++) for (int i = 0; i < n; i++) {
        int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
        F.row(f++) << a, b, d; F.row(f++) << a, d, c;
    }
    MeshConnectivity mesh(F);
    Eigen::VectorXd dofs;
    MidedgeAngleSinFormulation::initializeExtraDOFs(dofs, mesh, P);
    for (int k = 0; k < dofs.size(); k++) dofs[k] += 0.02 * u(rng);
    MonolayerRestState rs;
    int nf = F.rows();
    rs.thicknesses.assign(nf, 0.01); rs.lameAlpha.assign(nf, 1.0); rs.lameBeta.assign(nf, 0.5);
    ElasticShell<MidedgeAngleSinFormulation>::firstFundamentalForms(mesh, X, rs.abars);
    rs.bbars.assign(nf, Eigen::Matrix2d::Zero());
    StVKMaterial<MidedgeAngleSinFormulation> mat;
    Eigen::Matrix<double, 1, 9> d9; Eigen::Matrix<double, 9, 9> h9;
    Eigen::Matrix<double, 1, 21> d21; Eigen::Matrix<double, 21, 21> h21;
    double sink = 0, best = 1e30;
    for (int r = 0; r < reps; r++) {
        auto t0 = std::chrono::steady_clock::now();
        for (int i = 0; i < nf; i++) {
            sink += mat.stretchingEnergy(mesh, P, rs, i, &d9, &h9);
            sink += mat.bendingEnergy(mesh, P, dofs, rs, i, &d21, &h21);
            sink += h9(0, 0) + h21(20, 20) + d21(3);
        }
        double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (t < best) best = t;
    }
    printf("%d faces: %.3f us per face (E+g+H, stretching + midedge_sin bending), sink %g\n", nf, 1e6 * best / nf, sink);
}

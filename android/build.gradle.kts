// Android library module `io.github.sitar`: Kotlin wrapper + libsitar.so.
// The native library is built by cargo-ndk before every build:
//   cargo ndk -t arm64-v8a -t armeabi-v7a -t x86_64 -o src/main/jniLibs build --release -p sitar-ffi
// (run in this directory; cargo finds the workspace above it).
plugins {
    id("com.android.library") version "8.5.2"
    id("org.jetbrains.kotlin.android") version "1.9.24"
}

android {
    namespace = "io.github.sitar"
    compileSdk = 34

    defaultConfig {
        minSdk = 24
        consumerProguardFiles("consumer-rules.pro")
    }

    sourceSets["main"].jniLibs.srcDirs("src/main/jniLibs")

    compileOptions {
        sourceCompatibility = JavaVersion.VERSION_1_8
        targetCompatibility = JavaVersion.VERSION_1_8
    }
    kotlinOptions {
        jvmTarget = "1.8"
    }
}

val cargoNdk by tasks.registering(Exec::class) {
    description = "Builds libsitar.so for every ABI with cargo-ndk."
    workingDir = projectDir
    commandLine(
        "cargo", "ndk",
        "-t", "arm64-v8a", "-t", "armeabi-v7a", "-t", "x86_64",
        "-o", "src/main/jniLibs",
        "build", "--release", "-p", "sitar-ffi",
    )
}

tasks.named("preBuild") {
    dependsOn(cargoNdk)
}
